#pragma once
/// Output files (docs/conventions.md "Output files"): every regular file fivebar writes is first
/// written to a temporary sibling `.<name>.tmp.<pid>.<random>`, flushed and fsync'ed, then renamed
/// over the target. A failed run therefore leaves either the old file or the new one, never a
/// partial file, and no temporary behind; the temporaries of a killed run are removed by the next
/// write into the same directory. A target that is not a regular file (a device such as /dev/null,
/// a FIFO, /dev/stdout, any symbolic link) is written through, as the shell's `>` does.

#include <filesystem>
#include <memory>
#include <ostream>
#include <stdexcept>
#include <string>
#include <string_view>

namespace fivebar {

/// A file-system failure while writing output (disk full, permission denied, missing directory).
/// Not an InputError: the input was fine, the environment refused.
class IoError : public std::runtime_error {
 public:
  explicit IoError(const std::string& message) : std::runtime_error(message) {}
};

/// Writes `content` to `path` atomically. The parent directory must exist. On any failure the
/// temporary is removed, the previous file at `path` (if any) is untouched, and IoError is thrown
/// naming the path and the system error.
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

/// Streaming counterpart of write_file_atomic (CSV streams, large exports): write through
/// stream(), then commit() to fsync and rename. Destroying the object without commit() (an
/// exception, a bad input row) removes the temporary and leaves the target untouched, and so does
/// a signal (install_interrupt_cleanup). A file made by another program (openscad -o) goes the
/// same way: let the program write temp_path() (naming the format explicitly, as the temporary's
/// extension is not the target's), then commit().
class AtomicFile {
 public:
  /// Creates the temporary next to `path`; throws IoError when it cannot.
  explicit AtomicFile(std::filesystem::path path);
  ~AtomicFile();
  AtomicFile(AtomicFile&&) noexcept;
  AtomicFile& operator=(AtomicFile&&) noexcept;
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  /// The stream to write to; valid until commit() or destruction.
  std::ostream& stream();
  /// Flushes, fsyncs, closes and renames the temporary onto the target. Throws IoError (after
  /// removing the temporary) when any step fails. Calling it twice is an error (std::logic_error).
  void commit();
  /// Removes the temporary without touching the target; a no-op after commit().
  void discard() noexcept;

  const std::filesystem::path& path() const noexcept;
  /// The temporary's path (empty after commit() or discard()).
  const std::filesystem::path& temp_path() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Interrupted runs (docs/conventions.md "Output files": a failed run leaves no partial file): installs handlers for SIGINT,
/// SIGTERM, SIGHUP and SIGPIPE that remove the temporary of every AtomicFile still open in this
/// process and then let the signal take its default action, so the process still ends as killed by
/// that signal. Files already renamed into place are complete; nothing else is left behind. Call
/// once at the start of main(); further calls do nothing. Signals whose disposition is "ignore"
/// (nohup, a shell's background job) stay ignored.
void install_interrupt_cleanup();

/// Confines this process's writes: while a WriteFence on `root` is alive, AtomicFile,
/// write_file_atomic and make_directories refuse with IoError any target that does not land in
/// `root` (both made absolute and resolved through their symbolic links: a link inside the output
/// directory that points elsewhere is refused). The check and the write are two steps: another
/// process that swaps a directory for a link in between is not guarded against. Fences nest: every live fence must contain the target. `fivebar run`
/// fences its --out root, so no product can write outside it. Create and destroy fences on one
/// thread while no other thread writes.
class WriteFence {
 public:
  explicit WriteFence(const std::filesystem::path& root);
  ~WriteFence();
  WriteFence(const WriteFence&) = delete;
  WriteFence& operator=(const WriteFence&) = delete;
};

/// Creates `dir` and its missing parents (no-op when it exists); IoError naming the path otherwise.
void make_directories(const std::filesystem::path& dir);

/// `root / name` after lexical normalisation, refusing with InputError any result that is not
/// strictly inside `root` (absolute names, "..", an empty or "." name). Pure: touches no file;
/// symbolic links are not resolved.
std::filesystem::path resolve_output_dir(const std::filesystem::path& root, std::string_view name);

}  // namespace fivebar
