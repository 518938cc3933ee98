#pragma once
// The samples' command lines: CLI11 with the project's exit codes (0 ok, 1 failure, 2 usage).

#include <CLI/CLI.hpp>

namespace walk {

/// --help and --version print and give 0; any other parse error prints CLI11's message and
/// gives 2. Returns -1 when parsing succeeded.
inline int parse_command_line(CLI::App& app, int argc, char** argv) {
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        const int code = app.exit(e);
        return code == 0 ? 0 : 2;
    }
    return -1;
}

} // namespace walk
