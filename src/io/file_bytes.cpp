#include "io/file_bytes.hpp"

#include "bisect/error.hpp"
#include "bisect/threads.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <new>
#include <vector>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

namespace bisect {

FileBytes::FileBytes(const std::string &path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0)
    throw InputError(path, std::string("cannot open: ") + std::strerror(errno));
  struct Close {
    int fd;
    ~Close() { ::close(fd); }
  } close{fd};
  struct stat st;
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode))
    throw InputError(path, "not a regular file");
  size_ = std::size_t(st.st_size);
  if (size_ == 0)
    return;
  const std::size_t page = std::size_t(::sysconf(_SC_PAGESIZE));
  mapped_ = (size_ + page - 1) / page * page;
  void *p = ::mmap(nullptr, mapped_, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) {
    mapped_ = 0;
    throw std::bad_alloc();
  }
  data_ = static_cast<char *>(p);
  ::madvise(p, mapped_, MADV_HUGEPAGE); // where the kernel allows it; else nothing changes

  // Pieces of 8 MiB, each populated in one call (MADV_POPULATE_WRITE, Linux
  // 5.14; where it fails, read() faults the pages in) and filled by pread.
  constexpr std::size_t kPiece = std::size_t(8) << 20;
  constexpr int kPopulateWrite = 23; // MADV_POPULATE_WRITE
  const std::size_t pieces = (size_ + kPiece - 1) / kPiece;
  std::vector<int> failed(pieces, -1); // -1: fine; 0: the file ended early; else errno
  const int workers = int(std::clamp<std::size_t>(pieces, 1, std::size_t(threads())));
#pragma omp parallel for num_threads(workers) schedule(dynamic, 1)
  for (std::size_t k = 0; k < pieces; ++k) {
    const std::size_t begin = k * kPiece, len = std::min(kPiece, size_ - begin);
    ::madvise(data_ + begin, (len + page - 1) / page * page, kPopulateWrite);
    for (std::size_t done = 0; done < len;) {
      const ssize_t n = ::pread(fd, data_ + begin + done, len - done, off_t(begin + done));
      if (n < 0 && errno == EINTR)
        continue;
      if (n <= 0) {
        failed[k] = n < 0 ? errno : 0;
        break;
      }
      done += std::size_t(n);
    }
  }
  for (int err : failed)
    if (err >= 0) {
      release();
      throw InputError(path, err ? std::string("cannot read: ") + std::strerror(err)
                                 : "the file changed while it was read (it is shorter now)");
    }
}

FileBytes::~FileBytes() {
  release();
}

void FileBytes::release() {
  if (mapped_)
    ::munmap(data_, mapped_);
  data_ = nullptr;
  mapped_ = size_ = 0;
}

} // namespace bisect
