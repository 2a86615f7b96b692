/// \file base64.hpp
/// Base64 (RFC 4648, with padding): the binary arrays of mesh.vtu and the viewer page's data.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace ndc {

/// The `size` bytes at `data` in base64, appended to `out`.
inline void appendBase64(std::string& out, const void* data, std::size_t size) {
  static constexpr char kDigits[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* p = static_cast<const unsigned char*>(data);
  out.reserve(out.size() + (size + 2) / 3 * 4);
  for (std::size_t i = 0; i < size; i += 3) {
    const std::uint32_t a = p[i], b = i + 1 < size ? p[i + 1] : 0u,
                        c = i + 2 < size ? p[i + 2] : 0u;
    const std::uint32_t word = a << 16 | b << 8 | c;
    out += kDigits[word >> 18 & 63];
    out += kDigits[word >> 12 & 63];
    out += i + 1 < size ? kDigits[word >> 6 & 63] : '=';
    out += i + 2 < size ? kDigits[word & 63] : '=';
  }
}

/// The `size` bytes at `data` in base64.
inline std::string base64(const void* data, std::size_t size) {
  std::string out;
  appendBase64(out, data, size);
  return out;
}

}  // namespace ndc
