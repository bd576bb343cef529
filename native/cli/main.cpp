// Entry point of the `knitshade` tool: dispatches to registered subcommands.
#include <algorithm>
#include <cstdio>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include "cli.h"
#include "knit/version.h"
#ifdef KNIT_HAVE_RENDER
#include "render/build_info.h"
#endif

namespace knit::cli {

static std::vector<Command>& registry() {
  static std::vector<Command> commands;
  return commands;
}

bool register_command(const Command& cmd) {
  registry().push_back(cmd);
  return true;
}

static void print_help() {
  std::printf("knitshade %s: texture-free knitted-fabric rendering\n\n", knit::version());
  std::printf("usage: knitshade <command> [options]\n\ncommands:\n");
  auto cmds = registry();
  std::sort(cmds.begin(), cmds.end(),
            [](const Command& a, const Command& b) { return std::string(a.name) < b.name; });
  for (const Command& c : cmds) std::printf("  %-12s %s\n", c.name, c.summary);
  std::printf("\n`knitshade <command> --help` describes a command.\n");
}

}  // namespace knit::cli

int main(int argc, char** argv) {
  using namespace knit::cli;
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
    print_help();
    return argc < 2 ? 2 : 0;
  }
  std::string name = argv[1];
  if (name == "--version") {
    // The version, then what a bug report needs: the compiler, the vector
    // path this CPU takes, the libraries' versions.
    std::printf("knitshade %s\n", knit::version());
#ifdef KNIT_HAVE_RENDER
    for (const auto& [key, value] : knit::render::build_info()) std::printf("  %-14s %s\n", key.c_str(), value.c_str());
#endif
    return 0;
  }
  for (const Command& c : registry()) {
    if (name == c.name) {
      std::vector<std::string> args(argv + 2, argv + argc);
      try {
        return c.run(args);
      } catch (const UsageError& e) {
        std::fprintf(stderr, "knitshade %s: %s\n(see `knitshade %s --help`)\n", c.name,
                     e.message.c_str(), c.name);
        return 2;
      } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "knitshade %s: error: out of memory\n", c.name);
        return 1;
      } catch (const std::exception& e) {
        std::fprintf(stderr, "knitshade %s: error: %s\n", c.name, e.what());
        return 1;
      } catch (...) {
        std::fprintf(stderr, "knitshade %s: error: unexpected failure\n", c.name);
        return 1;
      }
    }
  }
  std::fprintf(stderr, "knitshade: unknown command '%s'\n", name.c_str());
  print_help();
  return 2;
}
