// The writer's literal-only zlib blocks (io/huffman_deflate.hpp): every
// stream inflates, with libdeflate (bisect's reader) and with zlib (VTK's
// and Python's), to the bytes given, and zlib_size() is the stream's size.
#include "io/huffman_deflate.hpp"

#include <catch2/catch.hpp>
#include <libdeflate.h>
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace {

using bisect::huffman_deflate::zlib_compress;
using bisect::huffman_deflate::zlib_size;

void require_round_trip(const std::vector<unsigned char> &data) {
  std::vector<unsigned char> z;
  zlib_compress(data.data(), data.size(), z);
  REQUIRE(z.size() == zlib_size(data.data(), data.size()));
  REQUIRE(z.size() >= 7);
  CHECK(z[0] == 0x78);
  CHECK((z[0] * 256 + z[1]) % 31 == 0);
  // libdeflate, which bisect's .vtu reader uses.
  std::vector<unsigned char> back(data.size() + 1, 0xAB);
  libdeflate_decompressor *d = libdeflate_alloc_decompressor();
  REQUIRE(d != nullptr);
  std::size_t got = 0;
  const libdeflate_result rc =
      libdeflate_zlib_decompress(d, z.data(), z.size(), back.data(), back.size(), &got);
  libdeflate_free_decompressor(d);
  REQUIRE(rc == LIBDEFLATE_SUCCESS);
  REQUIRE(got == data.size());
  REQUIRE((data.empty() || std::memcmp(back.data(), data.data(), data.size()) == 0));
  // zlib, which VTK and Python's zlib (meshio) use.
  std::vector<unsigned char> back2(data.size() + 1, 0xCD);
  uLongf len = uLongf(back2.size());
  REQUIRE(uncompress(back2.data(), &len, z.data(), uLong(z.size())) == Z_OK);
  REQUIRE(len == data.size());
  REQUIRE((data.empty() || std::memcmp(back2.data(), data.data(), data.size()) == 0));
}

std::uint64_t next(std::uint64_t &s) {
  s ^= s << 13;
  s ^= s >> 7;
  s ^= s << 17;
  return s;
}

} // namespace

TEST_CASE("huffman deflate: literal-only zlib streams inflate to their bytes with libdeflate and "
          "zlib, at the size announced",
          "[io]") {
  std::uint64_t s = 88172645463325252ull;
  SECTION("nothing") {
    require_round_trip({});
  }
  SECTION("one byte, one value repeated (a second code is made up)") {
    require_round_trip({7});
    require_round_trip(std::vector<unsigned char>(32768, 0));
    require_round_trip(std::vector<unsigned char>(1000, 255));
  }
  SECTION("uniform bytes (every literal, codes of 8 bits)") {
    std::vector<unsigned char> v(32768);
    for (unsigned char &c : v)
      c = static_cast<unsigned char>(next(s));
    require_round_trip(v);
  }
  SECTION("vertex ids: int32 with zero high bytes, as a refined mesh's connectivity") {
    std::vector<unsigned char> v(32768);
    for (std::size_t i = 0; i < v.size(); i += 4) {
      const std::uint32_t id = std::uint32_t(next(s) % 5'000'000);
      std::memcpy(v.data() + i, &id, 4);
    }
    require_round_trip(v);
    std::vector<unsigned char> z;
    zlib_compress(v.data(), v.size(), z);
    CHECK(z.size() < v.size() * 9 / 10); // the high bytes cost about a bit each
  }
  SECTION("counts that would make codes longer than 15 bits (Fibonacci weights)") {
    // Symbol k appears fib(k) times: an unrestricted Huffman code would be
    // 24 levels deep.
    std::vector<unsigned char> v;
    std::uint64_t a = 1, b = 1;
    for (int k = 0; k < 25; ++k) {
      v.insert(v.end(), std::size_t(a), static_cast<unsigned char>(k * 7));
      const std::uint64_t c = a + b;
      a = b;
      b = c;
    }
    REQUIRE(v.size() > 100000);
    require_round_trip(v);
  }
  SECTION("long runs of the same code length and of unused literals (the length code's "
          "repeats 16, 17, 18)") {
    // 200 distinct values with equal counts: lengths repeat far past 6;
    // the 56 unused literals give runs of zeros past 11 and between 3 and 10.
    std::vector<unsigned char> v;
    for (int r = 0; r < 40; ++r)
      for (int k = 0; k < 256; ++k)
        if (k % 64 < 50 || k == 255)
          v.push_back(static_cast<unsigned char>(k));
    require_round_trip(v);
    std::vector<unsigned char> w;
    for (int k = 0; k < 256; k += 17)
      w.insert(w.end(), std::size_t(1 + k), static_cast<unsigned char>(k));
    require_round_trip(w);
  }
  SECTION("random lengths and skews") {
    for (int trial = 0; trial < 200; ++trial) {
      const std::size_t n = std::size_t(next(s) % 40000);
      const unsigned spread = unsigned(1 + next(s) % 256);
      std::vector<unsigned char> v(n);
      for (unsigned char &c : v) {
        // Skewed: the minimum of two draws.
        const unsigned x = unsigned(next(s) % spread), y = unsigned(next(s) % spread);
        c = static_cast<unsigned char>(std::min(x, y));
      }
      INFO("trial " << trial << ", " << n << " bytes, spread " << spread);
      require_round_trip(v);
    }
  }
}
