#pragma once
// The command-line front end as a function, shared by the `fivebar` executable (fivebar_main.cpp)
// and the in-process CLI fuzzer (test/fuzz/fuzz_cli.cpp).

namespace fivebar::cli {

/// Runs `fivebar argv[1] ... argv[argc-1]` in this process: parses, runs the subcommand, prints to
/// std::cout / std::cerr, and returns the exit code of docs/conventions.md (0 ok, 1 check failed, 2 bad
/// input, 3 internal error or output not writable). Never throws for any argument vector and
/// never exits the process.
/// argv[0] is not read. Does not install signal handlers (the executable's main() does).
int main(int argc, char** argv);

}  // namespace fivebar::cli
