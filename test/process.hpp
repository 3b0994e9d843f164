#pragma once
// Running the real `fivebar` binary from tests with a time bound: posix_spawn in its own process
// group, stdin/stdout/stderr through files, polling wait, SIGKILL to the whole group when the
// bound is exceeded. Header-only; every test that runs the binary uses it.

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace fivebar::testing {

namespace fs = std::filesystem;

/// Seconds a test may wait for one child: FIVEBAR_TEST_CHILD_TIMEOUT_S, default `fallback`
/// (a sanitized build runs several times slower).
inline double child_timeout_s(double fallback = 20.0) {
  const char* v = std::getenv("FIVEBAR_TEST_CHILD_TIMEOUT_S");
  if (v != nullptr) {
    char* end = nullptr;
    const double s = std::strtod(v, &end);
    if (end != v && s > 0) return s;
  }
  return fallback;
}

inline std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// A fresh directory under the system temporary directory, removed with everything in it.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& prefix) {
    std::random_device rd;
    path_ = fs::temp_directory_path() / (prefix + "_" + std::to_string(::getpid()) + "_" + std::to_string(rd()));
    fs::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ec;
    fs::permissions(path_, fs::perms::owner_all, fs::perm_options::add, ec);
    fs::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

/// A child process started by spawn(); wait() collects it.
struct Child {
  pid_t pid = -1;
  fs::path out, err;
  std::chrono::steady_clock::time_point started;
};

struct Outcome {
  bool spawned = false;
  bool timed_out = false;
  int code = -1;    ///< exit status, or -1 when killed by a signal
  int signal = 0;   ///< the signal that ended the child, 0 if it exited
  std::string out;  ///< stdout
  std::string err;  ///< stderr
  double seconds = 0;
};

/// Starts `program args...` in `cwd` with `stdin_file` (may be empty: /dev/null) as stdin; stdout
/// and stderr go to files in `io_dir`. The child leads its own process group. Its environment is
/// this process's with `env` ("NAME=value" each) set on top, replacing a variable of that name.
inline Child spawn(const std::string& program, const std::vector<std::string>& args, const fs::path& cwd,
                   const fs::path& io_dir, const fs::path& stdin_file = {},
                   const std::vector<std::string>& env = {}) {
  Child c;
  static int counter = 0;
  const std::string tag = std::to_string(::getpid()) + "_" + std::to_string(++counter);
  c.out = io_dir / ("stdout_" + tag);
  c.err = io_dir / ("stderr_" + tag);
  std::vector<std::string> argv_s{program};
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::vector<std::string> env_s;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string var(*e);
    const std::string name = var.substr(0, var.find('='));
    const bool replaced = std::any_of(env.begin(), env.end(), [&](const std::string& x) {
      return x.substr(0, x.find('=')) == name;
    });
    if (!replaced) env_s.push_back(var);
  }
  env_s.insert(env_s.end(), env.begin(), env.end());
  std::vector<char*> envp;
  for (auto& e : env_s) envp.push_back(e.data());
  envp.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  const std::string in = stdin_file.empty() ? std::string("/dev/null") : stdin_file.string();
  posix_spawn_file_actions_addopen(&actions, 0, in.c_str(), O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, c.out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, 2, c.err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addchdir_np(&actions, cwd.c_str());
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK);
  posix_spawnattr_setpgroup(&attr, 0);
  sigset_t all, none;
  sigfillset(&all);
  sigemptyset(&none);
  posix_spawnattr_setsigdefault(&attr, &all);  // default dispositions, whatever the test runner set
  posix_spawnattr_setsigmask(&attr, &none);
  c.started = std::chrono::steady_clock::now();
  // posix_spawnp: a program name without '/' is looked up on PATH (mpirun); paths run as given.
  if (posix_spawnp(&c.pid, argv[0], &actions, &attr, argv.data(), envp.data()) != 0) c.pid = -1;
  posix_spawnattr_destroy(&attr);
  posix_spawn_file_actions_destroy(&actions);
  return c;
}

/// Waits for `c` at most `timeout_s` seconds from its start; past that, kills its process group.
inline Outcome wait(Child& c, double timeout_s) {
  Outcome r;
  if (c.pid <= 0) return r;
  r.spawned = true;
  int status = 0;
  const auto deadline = c.started + std::chrono::duration<double>(timeout_s);
  while (true) {
    const pid_t done = ::waitpid(c.pid, &status, WNOHANG);
    if (done == c.pid) break;
    if (std::chrono::steady_clock::now() > deadline) {
      r.timed_out = true;
      ::kill(-c.pid, SIGKILL);
      ::waitpid(c.pid, &status, 0);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - c.started).count();
  if (WIFEXITED(status)) {
    r.code = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    r.signal = WTERMSIG(status);
  }
  r.out = slurp(c.out);
  r.err = slurp(c.err);
  std::error_code ec;
  fs::remove(c.out, ec);
  fs::remove(c.err, ec);
  c.pid = -1;
  return r;
}

/// spawn() + wait().
inline Outcome run(const std::string& program, const std::vector<std::string>& args, const fs::path& cwd,
                   const fs::path& io_dir, double timeout_s, const fs::path& stdin_file = {},
                   const std::vector<std::string>& env = {}) {
  Child c = spawn(program, args, cwd, io_dir, stdin_file, env);
  return wait(c, timeout_s);
}

/// Every file and directory under `root`, relative and sorted, with the size of regular files:
/// "out/", "a.yaml 120".
inline std::vector<std::string> tree(const fs::path& root) {
  std::vector<std::string> out;
  std::error_code ec;
  if (!fs::exists(root, ec)) return out;
  for (auto it = fs::recursive_directory_iterator(root, ec); !ec && it != fs::recursive_directory_iterator();
       it.increment(ec)) {
    const std::string rel = fs::relative(it->path(), root).generic_string();
    if (it->is_directory(ec) && !it->is_symlink(ec)) {
      out.push_back(rel + "/");
    } else if (it->is_regular_file(ec)) {
      out.push_back(rel + " " + std::to_string(it->file_size(ec)));
    } else {
      out.push_back(rel);
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace fivebar::testing
