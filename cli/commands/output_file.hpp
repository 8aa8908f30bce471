#pragma once

#include <memory>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

namespace arbiter::cli {

/// Where the CLI puts a file it writes whole (a replay's trace and recording, a studio save).
struct OutputPlace {
  /// The file to replace: the path, or the file a symbolic link there leads to (followed through
  /// every link), so that a link stays a link and what it names gets the new text.
  std::string path;
  /// The path exists and is not a regular file (a FIFO, a terminal, a pipe), or names an open
  /// descriptor (named_descriptor()): it is written directly, as renaming a file over it would
  /// replace it.
  bool in_place = false;
};

OutputPlace output_place(const std::string& path);

/// The descriptor of this process that `path` names: standard output for its file
/// (is_standard_output()); N for /dev/fd/N and /proc/self/fd/N; 0, 1 and 2 for /dev/stdin,
/// /dev/stdout and /dev/stderr; so too through symbolic links to those. -1 when it names none.
/// What is written there goes through that descriptor's open file: opened again, the file would
/// get an offset of its own and be truncated, where the shell appends (3>>FILE) or has the
/// command write after what went there before; renamed over, it would be replaced.
int named_descriptor(const std::string& path);

/// A descriptor (close-on-exec) to write `path` with: a duplicate of the one it names
/// (named_descriptor()), written at that file's offset and appended to when the shell appends;
/// otherwise `path` opened, truncated or created (mode 0666 less the umask). -1 with errno when
/// it cannot be had (EBADF: the descriptor named is not open, or not for writing).
int open_output(const std::string& path);

/// Whether two paths name one file: the same file when both exist (through links and hard
/// links), the same normal path otherwise.
bool same_file(const std::string& a, const std::string& b);

/// Whether `path` is the file standard output is (/dev/stdout, /dev/fd/1, the file or pipe the
/// shell sent it to). Opened again, it would have an offset of its own (and be truncated, even
/// when the shell appends): what the command prints there would write over it.
bool is_standard_output(const std::string& path);

/// Whether one of `outputs` (an empty path is not one) is standard output's file: what the
/// command says besides (its report, its summary) goes to standard error then, so that standard
/// output holds that output alone, as whoever reads it (a pipe to jq, a trace reader) needs.
bool writes_standard_output(const std::vector<std::string>& outputs);

/// A file a command writes as it goes (a run's trace) or at once (a plot, a report), through
/// open_output().
class OutputStream : public std::ostream {
 public:
  OutputStream();
  OutputStream(const OutputStream&) = delete;
  OutputStream& operator=(const OutputStream&) = delete;
  /// Flushes what is held and closes the file.
  ~OutputStream() override;

  /// False, with why in error(), when `path` cannot be opened.
  bool open(const std::string& path);
  /// Why it could not be opened, or why a write failed, as the system says it ("No space left on
  /// device").
  std::string error() const;

 private:
  class Buffer;
  std::unique_ptr<Buffer> buffer_;
  int open_error_ = 0;
};

/// A file a command reads: its path, and what it is to the command ("the config being run").
struct CommandInput {
  std::string path;
  std::string what;
};

/// A file a command writes: its path, and the option that names it ("--trace").
struct CommandOutput {
  std::string path;
  std::string option;
};

/// False, with why on `err`, when one of `outputs` (those given: an empty path is not) is the
/// same file as one of `inputs` (an empty path is not one), which writing it would destroy, or as
/// another output, which it would write over. Before anything is written.
bool outputs_allowed(std::string_view command, const std::vector<CommandOutput>& outputs,
                     const std::vector<CommandInput>& inputs, std::ostream& err);

/// A file written whole or not at all: under a temporary name beside the file output_place()
/// names, renamed over it by commit(), so that a command that fails part way leaves the file as it
/// was. The file keeps the mode of the one it replaces; a new one gets the mode of any file
/// created there (0666 less the umask). A file output_place() writes in place is written directly,
/// through open_output().
/// Dropped before commit(), the temporary file is removed.
class AtomicFile {
 public:
  explicit AtomicFile(const std::string& path);
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile();

  /// Creates the temporary file (opens the file written in place); false, with why in `error()`,
  /// when it cannot.
  bool open();
  /// A descriptor of its own on the file open(), for a writer that writes it itself (a
  /// Recorder), which closes it; -1 when the system has none to give. A descriptor's file
  /// (named_descriptor()) is written at its offset, as appended to when the shell appends.
  int duplicate() const;
  /// Appends `text` (buffered); false once a write has failed.
  bool write(std::string_view text);
  /// Puts the file in place; false, with why in `error()`, when it could not be written (the file
  /// left as it was).
  bool commit();
  /// "cannot write 'PATH': REASON", naming the path as given.
  const std::string& error() const { return error_; }

 private:
  bool flush();
  /// Keeps the first error: what follows it is its consequence.
  void fail(int error);

  std::string given_;
  OutputPlace place_;
  std::string temp_;
  int fd_ = -1;
  std::string buffer_;
  std::string error_;
  bool done_ = false;
};

/// Writes `text` to `path` with an AtomicFile. False, with `error`, when it cannot.
bool write_atomically(const std::string& path, const std::string& text, std::string& error);

}  // namespace arbiter::cli
