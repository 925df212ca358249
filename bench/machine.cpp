// What the machine under bench/e2e.sh can do, as one JSON line, so that
// figures taken on different machines (each session of this project gets a
// fresh virtual machine) can be put side by side:
//
//   first_touch_gb_per_s  anonymous memory never touched before, on huge
//                         pages where the kernel gives them: what a refinement
//                         pays for the cell arrays it grows. On the virtual
//                         machines this project runs on, memory a process
//                         frees goes back to the host within seconds
//                         (virtio-balloon free page reporting), and touching
//                         it again cost 0.5-0.8 GB/s, against ~10 GB/s for
//                         memory the guest had touched a moment before
//                         (2026-12-06).
//   touch_at_once_gb_per_s  the same, at once after the first block was freed
//                         (the guest gives its pages back out);
//   touch_after_3s_gb_per_s  and 3 s after the second was freed (the host
//                         may have taken them back).
//   memset_gb_per_s       the first block written again: bandwidth.
//   random_read_ns        one read at a random place in 256 MiB (on huge
//                         pages where the kernel gives them), each read
//                         waiting for the last (a pointer chase): the latency
//                         the closure's and the checks' random reads wait on.
//   cbrt_ns               one std::cbrt in a chain: the core's speed on the
//                         quality's arithmetic.
//
// Usage: bisect_machine [MiB to touch, default 512]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numeric>
#include <random>
#include <thread>
#include <vector>

#include <sys/mman.h>

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Seconds to touch `bytes` of fresh anonymous memory (huge pages asked for),
// one write per 4 KiB page, then freed; with `memset_seconds`, also the time
// to write it all again before it is freed. -1 if it cannot be mapped.
double touch_fresh(std::size_t bytes, double *memset_seconds) {
  void *map = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (map == MAP_FAILED)
    return -1;
  madvise(map, bytes, MADV_HUGEPAGE);
  auto *p = static_cast<volatile char *>(map);
  auto t0 = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < bytes; i += 4096)
    p[i] = 1;
  const double touch = seconds_since(t0);
  if (memset_seconds) {
    t0 = std::chrono::steady_clock::now();
    std::memset(map, 2, bytes);
    *memset_seconds = seconds_since(t0);
  }
  munmap(map, bytes);
  return touch;
}

} // namespace

int main(int argc, char **argv) {
  const std::size_t mib = argc > 1 ? std::size_t(std::atol(argv[1])) : 512;
  const std::size_t bytes = mib << 20;

  // Fresh memory three times: first, at once after the first was freed,
  // and 3 s after the second was freed (by then the host has it back).
  double memset_seconds = 0;
  const double first_touch = touch_fresh(bytes, &memset_seconds);
  const double at_once = touch_fresh(bytes, nullptr);
  std::this_thread::sleep_for(std::chrono::seconds(3));
  const double after_3s = touch_fresh(bytes, nullptr);
  if (first_touch < 0 || at_once < 0 || after_3s < 0) {
    std::fprintf(stderr, "bisect_machine: cannot map %zu MiB\n", mib);
    return 2;
  }

  // A random cycle through 32 Mi slots of 8 bytes.
  const std::size_t slots = std::size_t(32) << 20;
  std::vector<std::uint32_t> order(slots);
  std::iota(order.begin(), order.end(), 0u);
  std::shuffle(order.begin() + 1, order.end(), std::mt19937_64(12345));
  // On huge pages, as bisect's own large arrays are (apps/bisect/huge_pages.cpp).
  void *chain =
      mmap(nullptr, slots * 8, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (chain == MAP_FAILED) {
    std::fprintf(stderr, "bisect_machine: cannot map 256 MiB\n");
    return 2;
  }
  madvise(chain, slots * 8, MADV_HUGEPAGE);
  auto *next = static_cast<std::uint64_t *>(chain);
  for (std::size_t i = 0; i < slots; ++i)
    next[order[i]] = order[(i + 1) % slots];
  const std::size_t steps = std::size_t(1) << 22;
  std::uint64_t at = 0;
  auto t0 = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < steps; ++i)
    at = next[at];
  const double chase = seconds_since(t0);
  munmap(chain, slots * 8);

  const std::size_t roots = std::size_t(1) << 24;
  double x = 2.5;
  t0 = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < roots; ++i)
    x = std::cbrt(x) + 1.5; // stays near 2.1: a chain of dependent roots
  const double cbrt = seconds_since(t0);

  std::printf("{\"case\": \"machine\", \"first_touch_gb_per_s\": %.2f, "
              "\"touch_at_once_gb_per_s\": %.2f, \"touch_after_3s_gb_per_s\": %.2f, "
              "\"memset_gb_per_s\": %.2f, \"random_read_ns\": %.1f, \"cbrt_ns\": %.2f, "
              "\"touched_mib\": %zu, \"check\": %llu}\n",
              double(bytes) / first_touch / 1e9, double(bytes) / at_once / 1e9,
              double(bytes) / after_3s / 1e9, double(bytes) / memset_seconds / 1e9,
              chase / double(steps) * 1e9, cbrt / double(roots) * 1e9, mib,
              (unsigned long long)(at + std::uint64_t(x)));
  return 0;
}
