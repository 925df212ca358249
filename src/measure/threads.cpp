#include "bisect/threads.hpp"

#include <atomic>
#include <thread>

namespace bisect {

namespace {
std::atomic<int> g_threads{0};
}

void set_threads(int n) {
  g_threads = n < 0 ? 0 : n;
}

int threads() {
  const int n = g_threads;
  if (n > 0)
    return n;
  const unsigned cores = std::thread::hardware_concurrency();
  return cores ? int(cores) : 1;
}

} // namespace bisect
