// Output files written as one transaction: every output of a command (mesh,
// quality CSV, slices) goes to a unique temporary file beside its target, and
// the targets are replaced only when all of them are complete. A failure or
// an interruption before that leaves every existing file as it was and no
// temporary file behind.
//
// Rules (README, "Files you give and get"):
//  - an output may not be an input of the command, nor another output;
//  - an existing regular file is replaced only with `force`;
//  - an existing output that is not a regular file (a FIFO, /dev/null,
//    /dev/stdout, a terminal) is written into directly, never replaced;
//  - a symbolic link is written through: its final target is replaced (or
//    created), the link stays;
//  - temporary names are unique (pid, counter, O_EXCL) and short enough for
//    any file name the file system accepts.
#pragma once

#include <string>
#include <vector>

namespace bisect {

class OutputSet {
public:
  // `inputs`: files the command reads, which no output may be.
  OutputSet(std::vector<std::string> inputs, bool force);
  ~OutputSet(); // removes the temporaries of an uncommitted set
  OutputSet(const OutputSet &) = delete;
  OutputSet &operator=(const OutputSet &) = delete;

  // Registers the output `path` and checks it (see the rules above); throws
  // InputError naming `path`. Returns a handle for file().
  int add(const std::string &path);

  // The file to write output `handle` into: a fresh temporary file (created
  // empty, with the mode of the file it will replace) or, for a non-regular
  // target, the target itself. Creates the temporary on first call.
  const std::string &file(int handle);

  // The name the user gave for output `handle`.
  const std::string &name(int handle) const { return outputs_[std::size_t(handle)].name; }

  // Renames every temporary onto its target, with SIGINT/SIGTERM/SIGHUP held
  // back so an interruption cannot leave some outputs new and some old.
  void commit();

private:
  struct Output {
    std::string name;    // as given
    std::string target;  // after following symbolic links
    bool direct = false; // existing non-regular file: written into
    std::string temp;    // the temporary, once created
    int slot = -1;       // its place in the signal-safe registry
  };
  std::vector<std::string> inputs_;
  bool force_;
  std::vector<Output> outputs_;
  bool committed_ = false;
};

// Removes every temporary file of uncommitted OutputSets and returns true,
// unless a commit has begun in this process: then it removes nothing and
// returns false (the outputs are being, or have been, renamed into place;
// the caller lets the run finish). Async-signal-safe (an atomic and unlink):
// the CLI's SIGINT/SIGTERM handler calls it, and on true ends the process
// at once; after true, a later commit() waits for that end.
bool remove_pending_outputs() noexcept;

// True once an OutputSet's commit has begun in this process (a signal after
// that has nothing left to undo).
bool outputs_committed() noexcept;

// The reason for a failed write in words: "no space left on device" for
// ENOSPC, and so on; "I/O error" when errno says nothing.
std::string write_failure(int err);

} // namespace bisect
