#pragma once
// What every handtrack program does with its command line and its errors (SPEC.md "Programs"):
// --help prints and exits 0; a bad argument or bad input is one line on stderr and a non-zero
// exit code.

#include <CLI/CLI.hpp>

#include <iostream>
#include <optional>
#include <string>

namespace handtrack {

// Longest message report_error() prints: a hostile input (a 10 MB string in a configuration
// file) is named, not echoed.
inline constexpr size_t kMaxErrorLine = 1000;

// Writes "PROGRAM: error: MESSAGE" as one line (newlines folded) and returns `code`. A message
// longer than kMaxErrorLine keeps its beginning (which file, which field) and its end (the reason)
// and says how much was left out between them.
inline int report_error(const std::string& program, const std::string& message, int code) {
  std::string line = message;
  if (line.size() > kMaxErrorLine) {
    const size_t keep = kMaxErrorLine / 2;
    line = message.substr(0, keep) + " [... " + std::to_string(message.size() - 2 * keep) + " characters left out ...] " +
           message.substr(message.size() - keep);
  }
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
