#pragma once
// The command line about itself (docs/install.md "Shell completion and man pages"): `fivebar help
// [CMD [SUB]]`, the house-style parse errors with a "did you mean", and the bash and zsh
// completions and man pages, all generated from the CLI11 tree that cli/commands.def builds (so
// they list every subcommand and option the binary accepts, and nothing else).

#include <CLI/CLI.hpp>

#include <string>
#include <string_view>
#include <vector>

namespace fivebar::cli {

/// The choice nearest to `word` (fivebar::nearest_name); empty when none is near enough.
std::string did_you_mean(std::string_view word, const std::vector<std::string>& choices);

/// The deepest subcommand the parse reached (`app` itself when none) and its path ("report accuracy").
CLI::App* parsed_command(CLI::App& app, std::string& path);

/// "fivebar CMD: error: <what>" (or "fivebar: error:") for a CLI11 parse error, naming an unknown
/// option with the nearest known one, and a pointer to `fivebar help CMD`.
void print_parse_error(CLI::App& app, const CLI::ParseError& e);

/// `fivebar help ...` (`words` after "help"): CMD [SUB] prints that command's help; --completion
/// bash|zsh prints the completion script; --man [CMD] prints a man page (fivebar(1), or
/// fivebar-CMD(1)). Returns the exit code; an unknown word is bad input (2) with a suggestion.
int run_help(CLI::App& app, const std::vector<std::string>& words);

/// The completion scripts and man pages run_help prints.
std::string bash_completion(CLI::App& app);
std::string zsh_completion(CLI::App& app);
std::string man_page(CLI::App& app, const std::string& command);

}  // namespace fivebar::cli
