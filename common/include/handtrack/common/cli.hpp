#pragma once
// What every handtrack program does with its command line and its errors (SPEC.md "Programs"):
// --help prints and exits 0; a bad argument or bad input is one line on stderr and a non-zero
// exit code.

#include <CLI/CLI.hpp>

#include <iostream>
#include <optional>
#include <string>

namespace handtrack {

// Writes "PROGRAM: error: MESSAGE" as one line (newlines folded) and returns `code`.
inline int report_error(const std::string& program, const std::string& message, int code) {
  std::string line = message;
  for (auto& c : line) {
    if (c == '\n') c = ' ';
  }
  std::cerr << program << ": error: " << line << "\n";
  return code;
}

// Parses argv into `app`. Returns nothing to go on, or the exit code main() should return:
// 0 after --help, `usage_code` after a bad command line (reported with report_error).
inline std::optional<int> parse_command_line(CLI::App& app, int argc, char** argv, const std::string& program,
                                             int usage_code) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return report_error(program, std::string(e.what()) + " (see --help)", usage_code);
  }
  return std::nullopt;
}

}  // namespace handtrack
