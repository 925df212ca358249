// A whole input file in memory, for the readers (.vtu, .msh).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace bisect {

// The bytes of the regular file `path`, read with read(2) into fresh
// anonymous memory, not mapped from the file: a file truncated by another
// process while it is read would make a mapping raise SIGBUS; here it is an
// InputError ("the file changed while it was read"). Errors name `path`:
// cannot open, not a regular file, cannot read.
//
// Reading is most of the cost of fresh memory: each page is cleared by the
// kernel on first touch (and on virtual machines a fault is slow). The
// buffer is therefore populated and filled in pieces of a few megabytes by
// all threads (bisect/threads.hpp), with transparent huge pages asked for.
class FileBytes {
public:
  explicit FileBytes(const std::string &path);
  ~FileBytes();
  FileBytes(const FileBytes &) = delete;
  FileBytes &operator=(const FileBytes &) = delete;

  const char *data() const { return data_; }
  std::size_t size() const { return size_; }
  std::string_view view() const { return {data_, size_}; }

private:
  void release();

  char *data_ = nullptr;
  std::size_t size_ = 0, mapped_ = 0;
};

} // namespace bisect
