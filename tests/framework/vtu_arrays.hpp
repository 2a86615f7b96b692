/// \file vtu_arrays.hpp
/// For tests: what a mesh writer writes, as text, and the DataArrays of a mesh.vtu decoded to
/// numbers, ASCII or binary (base64 of the zlib blocks of vtkZLibDataCompressor with a UInt64
/// header, docs/contracts.md 4.4).
#pragma once

#include <zlib.h>

#include <catch2/catch.hpp>

#include <cstdint>
#include <cstring>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace ndc::test {

/// What a writer `write(stream, result)` writes for `r` (mesh.ply, mesh.vtu, ..), as text.
template <class Result, class Write>
std::string text(const Result& r, Write write) {
  std::ostringstream out;
  write(out, r);
  return out.str();
}

/// The bytes of base64 `text` (RFC 4648, padded).
inline std::vector<unsigned char> unbase64(const std::string& text) {
  const std::string digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::vector<unsigned char> bytes;
  std::uint32_t word = 0;
  int bits = 0;
  for (char c : text) {
    if (c == '=') break;
    word = word << 6 | static_cast<std::uint32_t>(digits.find(c));
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      bytes.push_back(static_cast<unsigned char>(word >> bits & 0xff));
    }
  }
  return bytes;
}

/// The bytes of one binary DataArray: a base64 header of UInt64 (blocks, block size, last
/// partial size, compressed sizes) and, encoded apart, the zlib blocks.
inline std::vector<unsigned char> decodeArray(const std::string& body) {
  // The header's length follows from its block count (the first 8 bytes, 12 characters).
  const std::uint64_t blocks = [&] {
    std::uint64_t b = 0;
    std::memcpy(&b, unbase64(body.substr(0, 12)).data(), 8);
    return b;
  }();
  const std::size_t headerChars = ((3 + blocks) * 8 + 2) / 3 * 4;
  const std::vector<unsigned char> headerBytes = unbase64(body.substr(0, headerChars));
  std::vector<std::uint64_t> header(3 + blocks);
  std::memcpy(header.data(), headerBytes.data(), header.size() * 8);
  const std::vector<unsigned char> packed = unbase64(body.substr(headerChars));
  std::vector<unsigned char> bytes;
  std::size_t at = 0;
  for (std::uint64_t b = 0; b < blocks; ++b) {
    // Each block inflates to the block size, the last to the partial size when not 0.
    const bool last = b + 1 == blocks;
    uLongf size = static_cast<uLongf>(last && header[2] ? header[2] : header[1]);
    std::vector<unsigned char> block(size);
    REQUIRE(uncompress(block.data(), &size, packed.data() + at, header[3 + b]) == Z_OK);
    REQUIRE(size == block.size());
    bytes.insert(bytes.end(), block.begin(), block.end());
    at += header[3 + b];
  }
  REQUIRE(at == packed.size());
  return bytes;
}

/// Every DataArray of a mesh.vtu by name (the points' array is `Points`), decoded to doubles.
inline std::map<std::string, std::vector<double>> vtuArrays(const std::string& xml) {
  std::map<std::string, std::vector<double>> arrays;
  for (std::size_t at = xml.find("<DataArray"); at != std::string::npos;
       at = xml.find("<DataArray", at + 1)) {
    const std::size_t open = xml.find('>', at), close = xml.find("</DataArray>", open);
    const std::string tag = xml.substr(at, open - at);
    const auto attribute = [&](const std::string& key) {
      const std::size_t from = tag.find(key + "=\"");
      if (from == std::string::npos) return std::string();
      const std::size_t start = from + key.size() + 2;
      return tag.substr(start, tag.find('"', start) - start);
    };
    std::string name = attribute("Name");
    if (name.empty()) name = "Points";
    const std::string type = attribute("type");
    std::string body = xml.substr(open + 1, close - open - 1);
    std::vector<double>& values = arrays[name];
    if (attribute("format") == "ascii") {
      std::istringstream in(body);
      for (double v; in >> v;) values.push_back(v);
      continue;
    }
    REQUIRE(attribute("format") == "binary");
    body.erase(0, body.find_first_not_of(" \n"));
    body.erase(body.find_last_not_of(" \n") + 1);
    const std::vector<unsigned char> bytes = decodeArray(body);
    const auto take = [&]<class T>(T) {
      REQUIRE(bytes.size() % sizeof(T) == 0);
      for (std::size_t i = 0; i < bytes.size(); i += sizeof(T)) {
        T v;
        std::memcpy(&v, bytes.data() + i, sizeof(T));
        values.push_back(static_cast<double>(v));
      }
    };
    if (type == "Float64") take(double{});
    if (type == "Int32") take(std::int32_t{});
    if (type == "Int64") take(std::int64_t{});
    if (type == "UInt8") take(std::uint8_t{});
  }
  return arrays;
}

}  // namespace ndc::test
