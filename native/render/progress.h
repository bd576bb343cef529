// Progress display on stderr: a redrawn bar with ETA on a terminal, a plain
// line every 10% otherwise, nothing when quiet. Thread-safe add().
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <mutex>
#include <string>
#include <thread>

namespace knit::render {

enum class ProgressMode { Auto, Terminal, Plain, Quiet };

class Progress {
 public:
  // Auto picks Terminal when `out` is a terminal, Plain otherwise.
  Progress(ProgressMode mode, uint64_t total, std::string label, std::FILE* out = stderr);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void add(uint64_t n) { done_.fetch_add(n, std::memory_order_relaxed); }
  void finish();  // final line; idempotent
  ProgressMode mode() const { return mode_; }

  // "1:02:03" / "2:03" for a duration in seconds.
  static std::string format_duration(double seconds);

 private:
  void loop();
  void draw(bool final_line);

  ProgressMode mode_;
  uint64_t total_;
  std::string label_;
  std::FILE* out_;
  std::atomic<uint64_t> done_{0};
  std::chrono::steady_clock::time_point start_;
  int last_decile_ = 0;
  bool finished_ = false;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace knit::render
