#include "fivebar/io.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <cctype>
#include <mutex>
#include <set>
#include <random>
#include <streambuf>
#include <vector>

#include "fivebar/error.hpp"

namespace fivebar {
namespace fs = std::filesystem;

namespace {

std::string errno_text(int err) { return std::strerror(err); }

[[noreturn]] void throw_io(const fs::path& path, const std::string& what, int err) {
  throw IoError("cannot write '" + path.string() + "': " + what +
                (err != 0 ? ": " + errno_text(err) : std::string()));
}

/// Unbuffered-by-the-kernel output stream buffer over a POSIX descriptor: std::ofstream exposes
/// no descriptor to fsync.
class FdStreambuf : public std::streambuf {
 public:
  explicit FdStreambuf(int fd) : fd_(fd) { setp(buf_.data(), buf_.data() + buf_.size()); }
  /// errno of the first failed write, 0 if none.
  int error() const noexcept { return error_; }

 protected:
  int_type overflow(int_type ch) override {
    if (!drain()) return traits_type::eof();
    if (!traits_type::eq_int_type(ch, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(ch);
      pbump(1);
    }
    return traits_type::not_eof(ch);
  }
  int sync() override { return drain() ? 0 : -1; }

 private:
  bool drain() {
    const char* p = pbase();
    std::size_t left = static_cast<std::size_t>(pptr() - pbase());
    while (left > 0 && error_ == 0) {
      const ssize_t n = ::write(fd_, p, left);
      if (n < 0) {
        if (errno == EINTR) continue;
        error_ = errno;
        break;
      }
      p += n;
      left -= static_cast<std::size_t>(n);
    }
    setp(buf_.data(), buf_.data() + buf_.size());
    return error_ == 0;
  }

  int fd_;
  int error_ = 0;
  std::array<char, 1 << 16> buf_{};
};

std::uint64_t random_token() {
  // Seeded once per thread from the system's entropy source, never from the clock.
  thread_local std::mt19937_64 engine{[] {
    std::random_device device;
    return (static_cast<std::uint64_t>(device()) << 32) ^ device();
  }()};
  return engine();
}

// --- Temporaries still open, for the signal handler -------------------------------------------
//
// A fixed table in static storage: the handler may only read memory that no allocator touches and
// call async-signal-safe functions (unlink, raise). A slot is 0 free, 1 being filled, 2 live.

constexpr std::size_t kTempSlots = 256;
constexpr std::size_t kTempPathBytes = 4096;  // PATH_MAX on Linux

struct TempSlot {
  std::atomic<int> state{0};
  char path[kTempPathBytes]{};
};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs lock-free atomics");

TempSlot g_temp_slots[kTempSlots];

/// Records `path` for removal on a signal; -1 when the table is full or the path too long (the
/// temporary is then still removed on every normal path, only not on a signal).
int register_temp(const fs::path& path) {
  const std::string& text = path.native();
  if (text.size() >= kTempPathBytes) return -1;
  for (std::size_t i = 0; i < kTempSlots; ++i) {
    int expected = 0;
    if (g_temp_slots[i].state.compare_exchange_strong(expected, 1, std::memory_order_acquire)) {
      std::memcpy(g_temp_slots[i].path, text.c_str(), text.size() + 1);
      g_temp_slots[i].state.store(2, std::memory_order_release);
      return static_cast<int>(i);
    }
  }
  return -1;
}

void unregister_temp(int slot) noexcept {
  if (slot >= 0) g_temp_slots[slot].state.store(0, std::memory_order_release);
}

extern "C" void remove_temporaries_and_reraise(int sig) {
  const int saved_errno = errno;
  for (TempSlot& slot : g_temp_slots) {
    if (slot.state.load(std::memory_order_acquire) == 2) (void)::unlink(slot.path);
  }
  errno = saved_errno;
  // SA_RESETHAND restored the default action; the re-raised signal is delivered when this
  // handler returns, so the process ends exactly as the signal would have ended it.
  (void)::raise(sig);
}

// --- Write fences ----------------------------------------------------------------------------------

std::vector<fs::path>& fences() {
  static std::vector<fs::path> live;
  return live;
}

fs::path absolute_normal(const fs::path& p) {
  std::error_code ec;
  fs::path a = fs::absolute(p, ec);
  if (ec) a = p;
  a = a.lexically_normal();
  if (!a.has_filename() && a != a.root_path()) a = a.parent_path();  // "dir/" -> "dir"
  return a;
}

/// `p` absolute, normalised, with every symbolic link of its existing part resolved: where a
/// write to `p` really lands.
fs::path resolved(const fs::path& p) {
  std::error_code ec;
  fs::path r = fs::weakly_canonical(absolute_normal(p), ec);
  if (ec) return absolute_normal(p);
  if (!r.has_filename() && r != r.root_path()) r = r.parent_path();
  return r;
}

/// IoError unless `target` lands inside every live fence. Both sides are resolved through their
/// symbolic links, so a link inside the output directory cannot carry a write out of it.
void check_fences(const fs::path& target) {
  if (fences().empty()) return;
  const fs::path t = resolved(target);
  for (const fs::path& fence : fences()) {
    const fs::path root = resolved(fence);
    const fs::path inside = t.lexically_relative(root);
    if (inside.empty() || *inside.begin() == "..") {
      const fs::path lexical = absolute_normal(target).lexically_relative(absolute_normal(fence));
      const bool linked = !lexical.empty() && *lexical.begin() != "..";
      throw IoError("refusing to write '" + target.string() + "': " +
                    (linked ? "a symbolic link leads it to '" + t.string() + "', " : std::string()) +
                    "outside the output directory '" + fence.string() + "'");
    }
  }
}

/// Name of a temporary of write_file_atomic/AtomicFile: ".NAME.tmp.PID.TOKEN" (16 hex digits).
/// The PID, or 0 when `name` is not one.
long temporary_pid(const std::string& name) {
  if (name.size() < 24 || name[0] != '.') return 0;
  const std::size_t dot = name.rfind('.');
  if (dot == std::string::npos || name.size() - dot - 1 != 16) return 0;
  for (std::size_t i = dot + 1; i < name.size(); ++i) {
    if (!std::isxdigit(static_cast<unsigned char>(name[i]))) return 0;
  }
  const std::size_t pid_dot = name.rfind('.', dot - 1);
  if (pid_dot == std::string::npos || pid_dot < 5 || name.compare(pid_dot - 4, 4, ".tmp") != 0) return 0;
  long pid = 0;
  for (std::size_t i = pid_dot + 1; i < dot; ++i) {
    if (name[i] < '0' || name[i] > '9' || pid > 100000000) return 0;
    pid = pid * 10 + (name[i] - '0');
  }
  return pid;
}

/// Removes, once per directory and process, the temporaries that killed runs left in `dir`: those
/// whose process no longer exists (a live process's, or one we may not signal, are kept).
void remove_stale_temporaries(const fs::path& dir) {
  static std::set<fs::path> swept;
  static std::mutex swept_lock;  // products of a scene write from several threads
  const fs::path key = absolute_normal(dir.empty() ? fs::path(".") : dir);
  {
    const std::lock_guard<std::mutex> lock(swept_lock);
    if (!swept.insert(key).second) return;
  }
  std::error_code ec;
  for (fs::directory_iterator it(key, ec), end; !ec && it != end; it.increment(ec)) {
    const long pid = temporary_pid(it->path().filename().string());
    if (pid <= 0 || pid == ::getpid()) continue;
    if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;
    std::error_code ignored;
    if (it->is_regular_file(ignored) && !it->is_symlink(ignored)) fs::remove(it->path(), ignored);
  }
}

}  // namespace

void install_interrupt_cleanup() {
  static std::atomic<bool> installed{false};
  if (installed.exchange(true)) return;
  for (const int sig : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) {
    struct sigaction old_action {};
    if (::sigaction(sig, nullptr, &old_action) != 0) continue;
    if (old_action.sa_handler == SIG_IGN) continue;  // nohup, background jobs: keep ignoring
    struct sigaction action {};
    action.sa_handler = remove_temporaries_and_reraise;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESETHAND;
    (void)::sigaction(sig, &action, nullptr);
  }
}

WriteFence::WriteFence(const fs::path& root) { fences().push_back(absolute_normal(root)); }
WriteFence::~WriteFence() { fences().pop_back(); }

struct AtomicFile::Impl {
  fs::path target;
  fs::path temp;
  int fd = -1;
  int slot = -1;  ///< in the signal handler's table
  std::unique_ptr<FdStreambuf> buf;
  std::unique_ptr<std::ostream> os;
  bool committed = false;
  /// Written in place, as `>` does: the target is a device, a FIFO, a socket or a symbolic link
  /// (only a regular file is replaced atomically).
  bool through = false;

  void close_and_remove() noexcept {
    os.reset();
    buf.reset();
    if (fd >= 0) ::close(fd);
    fd = -1;
    if (!temp.empty()) ::unlink(temp.c_str());
    unregister_temp(slot);  // after the unlink: a signal in between finds the name and unlinks it again
    slot = -1;
    temp.clear();
  }
};

AtomicFile::AtomicFile(fs::path path) : impl_(std::make_unique<Impl>()) {
  impl_->target = std::move(path);
  const fs::path name = impl_->target.filename();
  if (name.empty() || name == "." || name == "..") {
    throw_io(impl_->target, "not a file name", 0);
  }
  check_fences(impl_->target);
  struct stat link_status {};
  if (::lstat(impl_->target.c_str(), &link_status) == 0) {
    struct stat status {};
    const bool exists = ::stat(impl_->target.c_str(), &status) == 0;
    if (exists && S_ISDIR(status.st_mode)) throw_io(impl_->target, "is a directory", 0);
    if (S_ISLNK(link_status.st_mode) || (exists && !S_ISREG(status.st_mode))) {
      // /dev/stdout, /dev/null, a FIFO, a link the user made: write through it, never replace it.
      const int fd = ::open(impl_->target.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
      if (fd < 0) throw_io(impl_->target, "cannot open", errno);
      impl_->through = true;
      impl_->fd = fd;
      impl_->buf = std::make_unique<FdStreambuf>(fd);
      impl_->os = std::make_unique<std::ostream>(impl_->buf.get());
      return;
    }
  }
  const fs::path dir = impl_->target.parent_path();
  remove_stale_temporaries(dir);
  for (int attempt = 0; attempt < 16; ++attempt) {
    char token[17];
    std::snprintf(token, sizeof token, "%016llx", static_cast<unsigned long long>(random_token()));
    const std::string temp_name = "." + name.string() + ".tmp." + std::to_string(::getpid()) + "." + token;
    const fs::path temp = dir.empty() ? fs::path(temp_name) : dir / temp_name;
    // Registered before it exists, so that no signal can fall between creation and registration.
    const int slot = register_temp(temp);
    const int fd = ::open(temp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0) unregister_temp(slot);
    if (fd >= 0) {
      impl_->temp = temp;
      impl_->slot = slot;
      impl_->fd = fd;
      impl_->buf = std::make_unique<FdStreambuf>(fd);
      impl_->os = std::make_unique<std::ostream>(impl_->buf.get());
      return;
    }
    if (errno != EEXIST) throw_io(impl_->target, "cannot create a temporary file", errno);
  }
  throw_io(impl_->target, "cannot find a free temporary name", EEXIST);
}

AtomicFile::~AtomicFile() { discard(); }
AtomicFile::AtomicFile(AtomicFile&&) noexcept = default;
AtomicFile& AtomicFile::operator=(AtomicFile&& other) noexcept {
  if (this != &other) {
    discard();
    impl_ = std::move(other.impl_);
  }
  return *this;
}

std::ostream& AtomicFile::stream() {
  if (!impl_ || !impl_->os) throw std::logic_error("AtomicFile::stream() after commit or discard");
  return *impl_->os;
}

void AtomicFile::commit() {
  if (!impl_ || !impl_->os) throw std::logic_error("AtomicFile::commit() after commit or discard");
  Impl& f = *impl_;
  f.os->flush();
  if (!*f.os || f.buf->error() != 0) {
    const int err = f.buf->error();
    f.close_and_remove();
    throw_io(f.target, "write failed", err);
  }
  if (::fsync(f.fd) != 0 && !(f.through && (errno == EINVAL || errno == EROFS || errno == ENOTSUP))) {
    const int err = errno;  // a pipe or a terminal cannot be synced: that is not a failure
    f.close_and_remove();
    throw_io(f.target, "fsync failed", err);
  }
  f.os.reset();
  f.buf.reset();
  const int fd = f.fd;
  f.fd = -1;
  if (::close(fd) != 0) {
    const int err = errno;
    f.close_and_remove();
    throw_io(f.target, "close failed", err);
  }
  if (f.through) {
    f.committed = true;
    return;
  }
  if (::rename(f.temp.c_str(), f.target.c_str()) != 0) {
    const int err = errno;
    f.close_and_remove();
    throw_io(f.target, "rename failed", err);
  }
  unregister_temp(f.slot);
  f.slot = -1;
  f.temp.clear();
  f.committed = true;
  // Make the rename itself durable; best effort (some file systems refuse fsync on directories).
  const fs::path dir = f.target.parent_path().empty() ? fs::path(".") : f.target.parent_path();
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    (void)::fsync(dfd);
    ::close(dfd);
  }
}

void AtomicFile::discard() noexcept {
  if (impl_) impl_->close_and_remove();
}

const fs::path& AtomicFile::path() const noexcept { return impl_->target; }
const fs::path& AtomicFile::temp_path() const noexcept { return impl_->through ? impl_->target : impl_->temp; }

void write_file_atomic(const fs::path& path, std::string_view content) {
  AtomicFile file(path);
  file.stream().write(content.data(), static_cast<std::streamsize>(content.size()));
  file.commit();
}

void make_directories(const fs::path& dir) {
  if (dir.empty()) return;
  check_fences(dir);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw IoError("cannot create directory '" + dir.string() + "': " + ec.message());
  if (!fs::is_directory(dir, ec)) throw IoError("'" + dir.string() + "' exists and is not a directory");
}

fs::path resolve_output_dir(const fs::path& root, std::string_view name) {
  const auto refuse = [&](const std::string& why) {
    throw InputError("output name '" + std::string(name) + "' " + why + " (output root '" +
                     root.string() + "')");
  };
  if (name.empty()) refuse("is empty");
  const fs::path rel(name);
  if (rel.has_root_name() || rel.has_root_directory()) refuse("must be relative");

  fs::path base = root.lexically_normal();
  if (!base.has_filename() && base != base.root_path()) base = base.parent_path();  // "out/" -> "out"
  const fs::path result = (base / rel).lexically_normal();
  const fs::path inside = result.lexically_relative(base);
  if (inside.empty() || inside == "." || *inside.begin() == "..") refuse("escapes the output root");
  // A trailing separator ("name/") normalises to a path with an empty last element.
  if (!result.has_filename()) return result.parent_path();
  return result;
}

}  // namespace fivebar
