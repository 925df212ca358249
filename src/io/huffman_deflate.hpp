// A zlib stream of one deflate block that codes every byte as a literal
// with its own Huffman code (no matches), for the .vtu writer's blocks
// whose bytes look random to deflate's match search but are far from
// uniform byte by byte, such as a refined mesh's connectivity (vertex ids
// whose high bytes repeat). Any zlib reader reads it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace bisect::huffman_deflate {

// The size in bytes of huffman_zlib(data, n)'s output, from the bytes'
// counts alone (without coding them).
std::size_t zlib_size(const unsigned char *data, std::size_t n);

// data[0, n) as a zlib stream (header, one final dynamic-Huffman block of
// literals, Adler-32), replacing out's contents.
void zlib_compress(const unsigned char *data, std::size_t n, std::vector<unsigned char> &out);

} // namespace bisect::huffman_deflate
