// A zlib stream of literals only, one dynamic-Huffman deflate block (RFC
// 1950, RFC 1951 3.2.7). See huffman_deflate.hpp.
#include "io/huffman_deflate.hpp"

#include <libdeflate.h>

#include <algorithm>
#include <array>
#include <cstring>

namespace bisect::huffman_deflate {
namespace {

constexpr int kSymbols = 257; // the 256 literals and the end of the block
constexpr int kEndOfBlock = 256;
constexpr int kMaxBits = 15;      // of a literal's code
constexpr int kMaxLengthBits = 7; // of a code length's code
// The order in which the code length code's own lengths are sent.
constexpr int kOrder[19] = {16, 17, 18, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1, 15};

// Lengths of a Huffman code for counts[0, n), none longer than max_bits:
// the optimal code's, recomputed from halved counts (a nonzero count stays
// nonzero) while one is too long. Symbols with count 0 get length 0. At
// least two symbols get a code (a dummy count of 1 for the first unused
// ones), so that the code is complete: zlib's inflate refuses a literal
// code that is not.
template <std::size_t N>
void code_lengths(std::array<std::uint32_t, N> counts, int max_bits,
                  std::array<std::uint8_t, N> &len) {
  int used = 0;
  for (std::uint32_t c : counts)
    used += c != 0;
  for (std::size_t s = 0; used < 2 && s < N; ++s)
    if (counts[s] == 0) {
      counts[s] = 1;
      ++used;
    }
  for (;;) {
    // Leaves first, then internal nodes as they are made; weights in
    // increasing order in each queue (two-queue construction).
    std::array<std::uint64_t, 2 * N> weight{};
    std::array<int, 2 * N> parent{};
    std::array<int, N> leaves{};
    int m = 0;
    for (std::size_t s = 0; s < N; ++s)
      if (counts[s])
        leaves[std::size_t(m++)] = int(s);
    std::sort(leaves.begin(), leaves.begin() + m, [&](int a, int b) {
      return counts[std::size_t(a)] != counts[std::size_t(b)]
                 ? counts[std::size_t(a)] < counts[std::size_t(b)]
                 : a < b;
    });
    for (int i = 0; i < m; ++i)
      weight[std::size_t(i)] = counts[std::size_t(leaves[std::size_t(i)])];
    int next_leaf = 0, next_node = m, made = m;
    auto take = [&]() {
      if (next_leaf < m &&
          (next_node == made || weight[std::size_t(next_leaf)] <= weight[std::size_t(next_node)]))
        return next_leaf++;
      return next_node++;
    };
    while (made < 2 * m - 1) {
      const int a = take(), b = take();
      weight[std::size_t(made)] = weight[std::size_t(a)] + weight[std::size_t(b)];
      parent[std::size_t(a)] = parent[std::size_t(b)] = made;
      ++made;
    }
    // Depths from the root (the last node) down; parents come after children.
    std::array<int, 2 * N> depth{};
    int longest = 0;
    for (int i = made - 2; i >= 0; --i) {
      depth[std::size_t(i)] = depth[std::size_t(parent[std::size_t(i)])] + 1;
      if (i < m)
        longest = std::max(longest, depth[std::size_t(i)]);
    }
    if (longest <= max_bits) {
      len.fill(0);
      for (int i = 0; i < m; ++i)
        len[std::size_t(leaves[std::size_t(i)])] = std::uint8_t(depth[std::size_t(i)]);
      return;
    }
    for (std::uint32_t &c : counts)
      if (c)
        c = (c + 1) / 2;
  }
}

// Canonical codes for the lengths (RFC 1951 3.2.2), bit-reversed: deflate
// sends a code's first bit first, into the low end of each byte.
template <std::size_t N>
void canonical_codes(const std::array<std::uint8_t, N> &len, std::array<std::uint16_t, N> &code) {
  std::array<std::uint16_t, kMaxBits + 2> count{}, next{};
  for (std::uint8_t l : len)
    ++count[l];
  count[0] = 0;
  std::uint16_t c = 0;
  for (int bits = 1; bits <= kMaxBits; ++bits) {
    c = std::uint16_t((c + count[std::size_t(bits - 1)]) << 1);
    next[std::size_t(bits)] = c;
  }
  for (std::size_t s = 0; s < N; ++s) {
    const int l = len[s];
    if (l == 0) {
      code[s] = 0;
      continue;
    }
    std::uint16_t v = next[std::size_t(l)]++, r = 0;
    for (int i = 0; i < l; ++i)
      r = std::uint16_t(r << 1 | ((v >> i) & 1));
    code[s] = r;
  }
}

// What the block sends: the literal code, and its lengths run-length coded
// with the code length code.
struct Plan {
  std::array<std::uint8_t, kSymbols> len{};
  std::array<std::uint16_t, kSymbols> code{};
  struct Step {
    std::uint8_t symbol, extra_bits, extra;
  };
  std::vector<Step> steps; // the lengths of the 257 literal codes and one distance code
  std::array<std::uint8_t, 19> cl_len{};
  std::array<std::uint16_t, 19> cl_code{};
  int hclen = 0;        // code length code lengths sent, less 4
  std::size_t bits = 0; // the block, the end of block included
};

Plan plan(const unsigned char *data, std::size_t n) {
  // Four tables of counts, summed: consecutive equal bytes (zeros in
  // vertex ids) do not wait on each other's increments.
  std::array<std::array<std::uint32_t, 256>, 4> part{};
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4) {
    ++part[0][data[i]];
    ++part[1][data[i + 1]];
    ++part[2][data[i + 2]];
    ++part[3][data[i + 3]];
  }
  for (; i < n; ++i)
    ++part[0][data[i]];
  std::array<std::uint32_t, kSymbols> counts{};
  for (int s = 0; s < 256; ++s)
    counts[std::size_t(s)] = part[0][std::size_t(s)] + part[1][std::size_t(s)] +
                             part[2][std::size_t(s)] + part[3][std::size_t(s)];
  counts[kEndOfBlock] = 1;
  Plan p;
  code_lengths(counts, kMaxBits, p.len);
  canonical_codes(p.len, p.code);
  // The lengths in order: 257 literal/length codes, then one distance code
  // of length 0 (no distance codes: the block has literals only).
  std::array<std::uint8_t, kSymbols + 1> lengths{};
  std::copy(p.len.begin(), p.len.end(), lengths.begin());
  auto step = [&](int symbol, int extra_bits, std::size_t extra) {
    p.steps.push_back({std::uint8_t(symbol), std::uint8_t(extra_bits), std::uint8_t(extra)});
  };
  for (std::size_t k = 0; k < lengths.size();) {
    const std::uint8_t v = lengths[k];
    std::size_t run = 1;
    while (k + run < lengths.size() && lengths[k + run] == v)
      ++run;
    std::size_t left = run;
    if (v == 0) {
      for (; left >= 11; left -= std::min<std::size_t>(left, 138))
        step(18, 7, std::min<std::size_t>(left, 138) - 11);
      if (left >= 3) {
        step(17, 3, left - 3);
        left = 0;
      }
    } else {
      step(v, 0, 0);
      --left;
      for (; left >= 3; left -= std::min<std::size_t>(left, 6))
        step(16, 2, std::min<std::size_t>(left, 6) - 3);
    }
    for (; left > 0; --left)
      step(v, 0, 0);
    k += run;
  }
  std::array<std::uint32_t, 19> cl_counts{};
  for (const Plan::Step &s : p.steps)
    ++cl_counts[s.symbol];
  code_lengths(cl_counts, kMaxLengthBits, p.cl_len);
  canonical_codes(p.cl_len, p.cl_code);
  int sent = 19;
  while (sent > 4 && p.cl_len[std::size_t(kOrder[sent - 1])] == 0)
    --sent;
  p.hclen = sent - 4;
  p.bits = 3 + 5 + 5 + 4 + 3 * std::size_t(sent);
  for (const Plan::Step &s : p.steps)
    p.bits += p.cl_len[s.symbol] + s.extra_bits;
  for (int s = 0; s < kSymbols; ++s)
    p.bits += std::size_t(counts[std::size_t(s)]) * p.len[std::size_t(s)];
  return p;
}

// Bits into a buffer with room to spare, the first bit sent in the lowest
// bit of each byte.
class BitWriter {
public:
  explicit BitWriter(unsigned char *at) : at_(at) {}
  // At most 32 bits at a time.
  void put(std::uint64_t value, int bits) {
    buf_ |= value << filled_;
    filled_ += bits;
    if (filled_ >= 32) {
      std::memcpy(at_, &buf_, 8); // 4 bytes past what is kept: room is left
      at_ += 4;
      buf_ >>= 32;
      filled_ -= 32;
    }
  }
  unsigned char *finish() {
    std::memcpy(at_, &buf_, 8);
    return at_ + (filled_ + 7) / 8;
  }

private:
  unsigned char *at_;
  std::uint64_t buf_ = 0;
  int filled_ = 0;
};

} // namespace

std::size_t zlib_size(const unsigned char *data, std::size_t n) {
  return 2 + (plan(data, n).bits + 7) / 8 + 4;
}

void zlib_compress(const unsigned char *data, std::size_t n, std::vector<unsigned char> &out) {
  const Plan p = plan(data, n);
  // The header (0x78 0x01: deflate, 32 KiB window, the fastest level), the
  // block and its 8 bytes of room for the writer, the Adler-32.
  out.resize(2 + (p.bits + 7) / 8 + 8 + 4);
  out[0] = 0x78;
  out[1] = 0x01;
  BitWriter w(out.data() + 2);
  w.put(1, 1); // the final block
  w.put(2, 2); // dynamic Huffman codes
  w.put(0, 5); // 257 literal/length codes
  w.put(0, 5); // one distance code
  w.put(std::uint64_t(p.hclen), 4);
  for (int k = 0; k < p.hclen + 4; ++k)
    w.put(p.cl_len[std::size_t(kOrder[k])], 3);
  for (const Plan::Step &s : p.steps) {
    w.put(p.cl_code[s.symbol], p.cl_len[s.symbol]);
    if (s.extra_bits)
      w.put(s.extra, s.extra_bits);
  }
  // Two literals a time (codes of at most 15 bits each).
  std::size_t i = 0;
  for (; i + 2 <= n; i += 2) {
    const unsigned char a = data[i], b = data[i + 1];
    w.put(p.code[a] | std::uint64_t(p.code[b]) << p.len[a], p.len[a] + p.len[b]);
  }
  if (i < n)
    w.put(p.code[data[i]], p.len[data[i]]);
  w.put(p.code[kEndOfBlock], p.len[kEndOfBlock]);
  unsigned char *end = w.finish();
  const std::uint32_t adler = libdeflate_adler32(1, data, n);
  end[0] = static_cast<unsigned char>(adler >> 24);
  end[1] = static_cast<unsigned char>(adler >> 16);
  end[2] = static_cast<unsigned char>(adler >> 8);
  end[3] = static_cast<unsigned char>(adler);
  out.resize(std::size_t(end + 4 - out.data()));
}

} // namespace bisect::huffman_deflate
