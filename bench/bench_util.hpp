// What the in-process benchmarks (bench.cpp, patch_proto.cpp) share.
#pragma once

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <string>

namespace bisect::bench {

using Clock = std::chrono::steady_clock;

// A figure of /proc/self/status in kB (VmRSS:, VmHWM:, ...), or -1.
inline long proc_status_kb(const char *field) {
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind(field, 0) == 0)
      return std::atol(line.c_str() + std::string(field).size());
  return -1;
}

inline double secs(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

} // namespace bisect::bench
