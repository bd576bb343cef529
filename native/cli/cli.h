// The `knitshade` command line tool: subcommands register themselves here.
#pragma once

#include <string>
#include <vector>

namespace knit::cli {

// A subcommand: `run` gets the arguments after the subcommand name and
// returns the process exit code (0 ok, 1 runtime error, 2 usage error).
struct Command {
  const char* name;
  const char* summary;
  int (*run)(const std::vector<std::string>& args);
};

// Called from a static initializer in each cmd_*.cpp.
bool register_command(const Command& cmd);

// Thrown for bad command-line usage; main prints it with the usage line.
struct UsageError {
  std::string message;
};

}  // namespace knit::cli
