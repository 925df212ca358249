// Large blocks on transparent huge pages, for the command-line tool only.
//
// A refinement grows a few arrays to hundreds of megabytes and the checks
// fill buffers of that size; on first touch each 4 KiB page costs a page
// fault, and on the virtual machines this project runs on a fault is
// expensive (the kernel's page-fault path was a tenth of `bisect refine`'s
// time). Asking for transparent huge pages (2 MiB) on blocks of 4 MiB or
// more cuts the faults 512-fold where the kernel allows it
// (/sys/kernel/mm/transparent_hugepage/enabled set to "madvise" or
// "always"); elsewhere madvise fails quietly and nothing changes.
//
// This replaces the global operator new of the executable, not of the
// library: a program linking libbisect keeps its own allocator. Sanitizer
// builds keep theirs too.
#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>

#include <sys/mman.h>

namespace {

constexpr std::size_t kHugePage = std::size_t(2) << 20;
constexpr std::size_t kThreshold = 2 * kHugePage;

void *allocate(std::size_t n) {
  void *p = std::malloc(n ? n : 1);
  if (!p)
    return nullptr;
  if (n >= kThreshold) {
    // The whole huge pages inside the block.
    const auto begin = (reinterpret_cast<std::uintptr_t>(p) + kHugePage - 1) & ~(kHugePage - 1);
    const auto end = (reinterpret_cast<std::uintptr_t>(p) + n) & ~(kHugePage - 1);
    if (end > begin)
      madvise(reinterpret_cast<void *>(begin), end - begin, MADV_HUGEPAGE);
  }
  return p;
}

void *allocate_or_throw(std::size_t n) {
  for (;;) {
    if (void *p = allocate(n))
      return p;
    std::new_handler handler = std::get_new_handler();
    if (!handler)
      throw std::bad_alloc();
    handler();
  }
}

} // namespace

void *operator new(std::size_t n) {
  return allocate_or_throw(n);
}
void *operator new[](std::size_t n) {
  return allocate_or_throw(n);
}
void *operator new(std::size_t n, const std::nothrow_t &) noexcept {
  return allocate(n);
}
void *operator new[](std::size_t n, const std::nothrow_t &) noexcept {
  return allocate(n);
}
void operator delete(void *p) noexcept {
  std::free(p);
}
void operator delete[](void *p) noexcept {
  std::free(p);
}
void operator delete(void *p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void *p, std::size_t) noexcept {
  std::free(p);
}
void operator delete(void *p, const std::nothrow_t &) noexcept {
  std::free(p);
}
void operator delete[](void *p, const std::nothrow_t &) noexcept {
  std::free(p);
}

#endif
