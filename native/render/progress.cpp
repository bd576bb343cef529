#include "render/progress.h"

#include <unistd.h>

#include <cmath>

namespace knit::render {

Progress::Progress(ProgressMode mode, uint64_t total, std::string label, std::FILE* out)
    : mode_(mode), total_(total), label_(std::move(label)), out_(out) {
  if (mode_ == ProgressMode::Auto) mode_ = isatty(fileno(out_)) ? ProgressMode::Terminal : ProgressMode::Plain;
  start_ = std::chrono::steady_clock::now();
  if (mode_ != ProgressMode::Quiet && total_ > 0) thread_ = std::thread([this] { loop(); });
}

Progress::~Progress() { finish(); }

std::string Progress::format_duration(double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  const long t = static_cast<long>(std::lround(s));
  char buf[32];
  if (t >= 3600)
    std::snprintf(buf, sizeof buf, "%ld:%02ld:%02ld", t / 3600, (t / 60) % 60, t % 60);
  else
    std::snprintf(buf, sizeof buf, "%ld:%02ld", t / 60, t % 60);
  return buf;
}

void Progress::loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  const auto period = mode_ == ProgressMode::Terminal ? std::chrono::milliseconds(200) : std::chrono::milliseconds(500);
  while (!stop_) {
    cv_.wait_for(lock, period, [this] { return stop_; });
    if (!stop_) draw(false);
  }
}

void Progress::draw(bool final_line) {
  const uint64_t done = std::min(done_.load(std::memory_order_relaxed), total_);
  const double frac = total_ > 0 ? static_cast<double>(done) / static_cast<double>(total_) : 1.0;
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double eta = done > 0 ? elapsed * (1.0 - frac) / frac : NAN;
  if (mode_ == ProgressMode::Terminal) {
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(frac * kWidth);
    std::string bar(static_cast<size_t>(filled), '#');
    bar.append(static_cast<size_t>(kWidth - filled), '-');
    std::fprintf(out_, "\r%s [%s] %5.1f%%  elapsed %s  ETA %s   ", label_.c_str(), bar.c_str(), 100.0 * frac,
                 format_duration(elapsed).c_str(), final_line ? "0:00" : format_duration(eta).c_str());
    if (final_line) std::fputc('\n', out_);
    std::fflush(out_);
  } else if (mode_ == ProgressMode::Plain) {
    const int decile = static_cast<int>(frac * 10.0);
    if (decile > last_decile_ && (decile < 10 || final_line)) {
      last_decile_ = decile;
      std::fprintf(out_, "%s: %3d%%  elapsed %s  ETA %s\n", label_.c_str(), decile * 10,
                   format_duration(elapsed).c_str(), format_duration(final_line ? 0.0 : eta).c_str());
      std::fflush(out_);
    }
  }
}

void Progress::finish() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (finished_) return;
    finished_ = true;
    stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  if (mode_ != ProgressMode::Quiet && total_ > 0) draw(true);
}

}  // namespace knit::render
