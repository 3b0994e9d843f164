// `fivebar help`, house-style parse errors, and the completion scripts and man pages generated from
// the CLI11 tree (cli/help.hpp).

#include "help.hpp"

#include <algorithm>
#include <iostream>
#include <sstream>

#include "common.hpp"
#include "fivebar/suggest.hpp"
#include "fivebar/version.hpp"

namespace fivebar::cli {
namespace {

std::vector<CLI::App*> subcommands_of(CLI::App& app) {
  return app.get_subcommands([](CLI::App*) { return true; });
}

std::vector<std::string> names_of(const std::vector<CLI::App*>& subs) {
  std::vector<std::string> names;
  for (const CLI::App* s : subs) names.push_back(s->get_name());
  return names;
}

/// Every name of every option of `app` ("-t", "--theta"), positionals and the help flag included
/// only as flags ("--help"); the order CLI11 holds them in.
std::vector<std::string> option_names(CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::Option* o : app.get_options()) {
    for (const std::string& s : o->get_snames()) names.push_back("-" + s);
    for (const std::string& l : o->get_lnames()) names.push_back("--" + l);
  }
  return names;
}

/// A word from the command line, printable: control characters shown as '?'.
std::string shown(std::string_view word) {
  std::string out;
  for (const char c : word) out += (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) ? '?' : c;
  return out;
}

/// The first line of a description, without the characters a shell or zsh spec would read.
std::string one_line(std::string text, std::size_t limit = 200) {
  text = text.substr(0, text.find('\n'));
  std::string out;
  for (const char c : text) {
    if (c == '\'' || c == '"' || c == '`' || c == '$' || c == '\\') continue;
    out += (c == '[' ? '(' : c == ']' ? ')' : c == ':' ? ';' : c);
  }
  if (out.size() > limit) out = out.substr(0, limit - 3) + "...";
  return out;
}

/// A command named by `words` ("report", "accuracy"), or nullptr; `path` gets its words as found.
CLI::App* find_command(CLI::App& app, const std::vector<std::string>& words, std::string& path, std::string& error) {
  CLI::App* level = &app;
  for (const std::string& word : words) {
    CLI::App* match = nullptr;
    for (CLI::App* sub : subcommands_of(*level)) {
      if (sub->check_name(word)) match = sub;
    }
    if (match == nullptr) {
      const std::vector<std::string> known = names_of(subcommands_of(*level));
      error = "unknown subcommand '" + shown(word) + "'" + (path.empty() ? "" : " of '" + path + "'");
      if (const std::string near = did_you_mean(word, known); !near.empty()) error += " (did you mean '" + near + "'?)";
      std::string list;
      for (const std::string& k : known) list += (list.empty() ? "" : ", ") + k;
      error += known.empty() ? " ('" + path + "' has no subcommands)" : " (known: " + list + ")";
      return nullptr;
    }
    path += (path.empty() ? "" : " ") + match->get_name();
    level = match;
  }
  return level;
}

// --- bash ------------------------------------------------------------------------------------------

void bash_cases(CLI::App& app, const std::string& path, std::ostringstream& out) {
  std::string options;
  for (const std::string& n : option_names(app)) options += (options.empty() ? "" : " ") + n;
  std::string subs;
  for (const std::string& n : names_of(subcommands_of(app))) subs += (subs.empty() ? "" : " ") + n;
  if (path.empty()) subs += " help";
  out << "    \"" << path << "\") opts=\"" << options << "\"; subs=\"" << subs << "\" ;;\n";
  for (CLI::App* sub : subcommands_of(app)) bash_cases(*sub, path.empty() ? sub->get_name() : path + " " + sub->get_name(), out);
}

// --- zsh -------------------------------------------------------------------------------------------

void zsh_function(CLI::App& app, const std::string& function, std::ostringstream& out) {
  const std::vector<CLI::App*> subs = subcommands_of(app);
  out << function << "() {\n";
  if (!subs.empty()) {
    out << "  local -a subs\n  subs=(\n";
    for (CLI::App* s : subs) out << "    '" << s->get_name() << ":" << one_line(s->get_description(), 70) << "'\n";
    if (app.get_parent() == nullptr) out << "    'help:show a subcommand help'\n";
    out << "  )\n";
  }
  out << "  _arguments -C \\\n";
  for (const CLI::Option* o : app.get_options()) {
    if (o->get_positional() && !o->nonpositional()) continue;
    const bool flag = o->get_expected_max() == 0 || o->get_type_size_max() == 0;
    std::vector<std::string> names;
    for (const std::string& s : o->get_snames()) names.push_back("-" + s);
    for (const std::string& l : o->get_lnames()) names.push_back("--" + l);
    for (const std::string& n : names) {
      out << "    '" << n << "[" << one_line(o->get_description(), 70) << "]" << (flag ? "" : ":value:_files") << "' \\\n";
    }
  }
  if (!subs.empty()) {
    out << "    '1: :->sub' '*:: :->args' && return 0\n";
    out << "  case $state in\n    sub) _describe 'subcommand' subs ;;\n    args)\n      case $words[1] in\n";
    for (CLI::App* s : subs) out << "        " << s->get_name() << ") " << function << "_" << s->get_name() << " ;;\n";
    if (app.get_parent() == nullptr) out << "        help) _describe 'subcommand' subs ;;\n";
    out << "      esac ;;\n  esac\n}\n\n";
    for (CLI::App* s : subs) zsh_function(*s, function + "_" + s->get_name(), out);
  } else {
    out << "    '*:file:_files'\n}\n\n";
  }
}

// --- man -------------------------------------------------------------------------------------------

std::string first_line(const std::string& text) { return text.substr(0, text.find('\n')); }

/// Text for troff: backslashes escaped, a line starting with '.' or '\'' protected, '-' as \-.
std::string roff(const std::string& text) {
  std::string out;
  bool line_start = true;
  for (const char c : text) {
    if (line_start && (c == '.' || c == '\'')) out += "\\&";
    if (c == '\\') out += "\\e";
    else if (c == '-') out += "\\-";
    else out += c;
    line_start = c == '\n';
  }
  return out;
}

void man_options(CLI::App& app, std::ostringstream& out) {
  std::ostringstream positionals;
  std::ostringstream options;
  for (const CLI::Option* o : app.get_options()) {
    if (o->get_positional() && !o->nonpositional()) {
      positionals << ".TP\n.I " << roff(o->get_name(true)) << "\n" << roff(o->get_description()) << "\n";
      continue;
    }
    std::string names;
    for (const std::string& s : o->get_snames()) names += (names.empty() ? "" : ", ") + std::string("\\fB\\-") + s + "\\fR";
    for (const std::string& l : o->get_lnames()) names += (names.empty() ? "" : ", ") + std::string("\\fB\\-\\-") + roff(l) + "\\fR";
    const bool flag = o->get_expected_max() == 0 || o->get_type_size_max() == 0;
    std::string type = o->get_type_name();
    type = type.substr(0, type.find(':'));
    if (!flag && !type.empty()) names += " \\fI" + roff(type) + "\\fR";
    options << ".TP\n" << names << "\n" << roff(o->get_description()) << "\n";
  }
  if (!positionals.str().empty()) out << ".SH ARGUMENTS\n" << positionals.str();
  if (!options.str().empty()) out << ".SH OPTIONS\n" << options.str();
}

}  // namespace

std::string did_you_mean(std::string_view word, const std::vector<std::string>& choices) {
  return nearest_name(word, choices);
}

CLI::App* parsed_command(CLI::App& app, std::string& path) {
  CLI::App* level = &app;
  for (bool deeper = true; deeper;) {
    deeper = false;
    for (CLI::App* sub : subcommands_of(*level)) {
      if (sub->parsed()) {
        path += (path.empty() ? "" : " ") + sub->get_name();
        level = sub;
        deeper = true;
        break;
      }
    }
  }
  return level;
}

void print_parse_error(CLI::App& app, const CLI::ParseError& e) {
  std::string path;
  CLI::App* command = parsed_command(app, path);
  const std::string prefix = path.empty() ? "fivebar: error: " : "fivebar " + path + ": error: ";
  std::string message = e.what();
  if (dynamic_cast<const CLI::ExtrasError*>(&e) != nullptr) {
    const std::vector<std::string> extras = command->remaining();
    const std::vector<std::string> known = option_names(*command);
    // Unknown options first; the words after one are most likely its value, so plain words are
    // named only when no option was unknown.
    std::string listed;
    for (const std::string& x : extras) {
      const std::string word = x.substr(0, x.find('='));
      if (word.size() > 1 && word[0] == '-') {
        listed += (listed.empty() ? "unknown option '" : ", unknown option '") + shown(word) + "'";
        if (const std::string near = did_you_mean(word, known); !near.empty()) listed += " (did you mean '" + near + "'?)";
      }
    }
    for (const std::string& x : extras) {
      if (!listed.empty() && listed.rfind("unknown option", 0) == 0) break;
      if (x.size() > 1 && x[0] == '-') continue;
      listed += (listed.empty() ? "unexpected argument '" : ", unexpected argument '") + shown(x) + "'";
    }
    if (!listed.empty()) message = listed;
  }
  std::cerr << prefix << message << "\n"
            << "fivebar: hint: 'fivebar help" << (path.empty() ? "" : " " + path) << "' lists the options\n";
}

int run_help(CLI::App& app, const std::vector<std::string>& words) {
  if (!words.empty() && words[0] == "--completion") {
    const std::string shell = words.size() == 2 ? words[1] : "";
    if (shell == "bash") std::cout << bash_completion(app);
    else if (shell == "zsh") std::cout << zsh_completion(app);
    else {
      std::cerr << "fivebar help: error: --completion takes one shell, bash or zsh\n";
      return kBadInput;
    }
    return kOk;
  }
  std::vector<std::string> command = words;
  const bool man = !words.empty() && words[0] == "--man";
  if (man) command.erase(command.begin());
  std::string path;
  std::string error;
  CLI::App* target = find_command(app, command, path, error);
  if (target == nullptr) {
    std::cerr << "fivebar help: error: " << error << "\n";
    return kBadInput;
  }
  if (man) {
    std::cout << man_page(app, path);
    return kOk;
  }
  const std::string prev = path.rfind(' ') == std::string::npos ? "fivebar" : "fivebar " + path.substr(0, path.rfind(' '));
  std::cout << (target == &app ? app.help() : target->help(prev));
  return kOk;
}

std::string bash_completion(CLI::App& app) {
  std::ostringstream out;
  out << "# bash completion for fivebar " << version() << ", generated by `fivebar help --completion bash`\n"
      << "_fivebar() {\n"
      << "  local cur=\"${COMP_WORDS[COMP_CWORD]}\" path=\"\" word i opts subs\n"
      << "  for ((i = 1; i < COMP_CWORD; i++)); do\n"
      << "    word=\"${COMP_WORDS[i]}\"\n"
      << "    [[ $word == -* ]] && continue\n"
      << "    _fivebar_level \"$path\"\n"
      << "    if [[ \" $subs \" == *\" $word \"* && $word != help ]]; then path=\"${path:+$path }$word\";\n"
      << "    elif [[ -z $path && $word == help ]]; then path=help; fi\n"
      << "  done\n"
      << "  if [[ $path == help* ]]; then _fivebar_level \"\"; COMPREPLY=($(compgen -W \"$subs\" -- \"$cur\")); return; fi\n"
      << "  _fivebar_level \"$path\"\n"
      << "  if [[ $cur == -* ]]; then COMPREPLY=($(compgen -W \"$opts\" -- \"$cur\"));\n"
      << "  elif [[ -n $subs ]]; then COMPREPLY=($(compgen -W \"$subs\" -- \"$cur\")); fi\n"
      << "}\n"
      << "_fivebar_level() {\n"
      << "  case \"$1\" in\n";
  bash_cases(app, "", out);
  out << "    *) opts=\"\"; subs=\"\" ;;\n"
      << "  esac\n"
      << "}\n"
      << "complete -o default -F _fivebar fivebar\n";
  return out.str();
}

std::string zsh_completion(CLI::App& app) {
  std::ostringstream out;
  out << "#compdef fivebar\n# zsh completion for fivebar " << version() << ", generated by `fivebar help --completion zsh`\n\n";
  zsh_function(app, "_fivebar", out);
  out << "_fivebar \"$@\"\n";
  return out.str();
}

std::string man_page(CLI::App& app, const std::string& command) {
  std::string path;
  std::string error;
  std::vector<std::string> words;
  std::istringstream split(command);
  for (std::string w; split >> w;) words.push_back(w);
  CLI::App* target = find_command(app, words, path, error);
  if (target == nullptr) return {};
  std::string title = "fivebar" + (path.empty() ? "" : "-" + path);
  std::replace(title.begin(), title.end(), ' ', '-');
  std::string upper = title;
  std::transform(upper.begin(), upper.end(), upper.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  std::ostringstream out;
  out << ".\\\" Generated by `fivebar help --man" << (path.empty() ? "" : " " + path) << "` from the command line itself.\n"
      << ".TH " << roff(upper) << " 1 \"\" \"fivebar " << version() << "\" \"User Commands\"\n"
      << ".SH NAME\n" << roff(title) << " \\- " << roff(first_line(target->get_description())) << "\n"
      << ".SH SYNOPSIS\n.B fivebar" << (path.empty() ? "" : " " + roff(path)) << "\n"
      << (subcommands_of(*target).empty() ? "[\\fIOPTIONS\\fR] \\fIARGUMENTS\\fR\n" : "\\fISUBCOMMAND\\fR [\\fIOPTIONS\\fR]\n")
      << ".SH DESCRIPTION\n" << roff(target->get_description()) << "\n";
  man_options(*target, out);
  if (const std::vector<CLI::App*> subs = subcommands_of(*target); !subs.empty()) {
    out << ".SH SUBCOMMANDS\n";
    for (CLI::App* s : subs) {
      std::string page = title + "-" + s->get_name();
      out << ".TP\n.B " << roff(s->get_name()) << "\n" << roff(first_line(s->get_description())) << " (see \\fB" << roff(page)
          << "\\fR(1))\n";
    }
    if (target == &app) out << ".TP\n.B help \\fR[\\fISUBCOMMAND\\fR]\nThe help of a subcommand; \\fBhelp \\-\\-completion bash\\fR|\\fBzsh\\fR prints a completion script, \\fBhelp \\-\\-man\\fR [\\fISUBCOMMAND\\fR] a man page.\n";
  }
  if (const std::string footer = target->get_footer(); !footer.empty()) out << ".SH NOTES\n" << roff(footer) << "\n";
  out << ".SH SEE ALSO\n" << (path.empty() ? "" : "\\fBfivebar\\fR(1), ")
      << "the documents installed in share/fivebar/docs (docs/install.md)\n";
  return out.str();
}

}  // namespace fivebar::cli
