#pragma once
// UTF-8 as the readers check it and the diagnostics print it. Internal to the engine.

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace arbiter::detail {

/// The code point of the valid UTF-8 sequence at `at` in `text`, and its length in bytes; a
/// length of 0 when the bytes there are not valid UTF-8 (a stray or missing continuation byte,
/// an overlong form, a surrogate, beyond U+10FFFF).
struct Utf8Char {
  std::uint32_t code = 0;
  std::size_t length = 0;
};

inline Utf8Char utf8_char(std::string_view text, std::size_t at) {
  const auto byte = static_cast<unsigned char>(text[at]);
  std::size_t length = 0;
  std::uint32_t code = 0;
  if (byte < 0x80) {
    return {byte, 1};
  } else if ((byte & 0xE0) == 0xC0) {
    length = 2, code = byte & 0x1F;
  } else if ((byte & 0xF0) == 0xE0) {
    length = 3, code = byte & 0x0F;
  } else if ((byte & 0xF8) == 0xF0) {
    length = 4, code = byte & 0x07;
  } else {
    return {};
  }
  if (length > text.size() - at) return {};
  for (std::size_t k = 1; k < length; ++k) {
    const auto next = static_cast<unsigned char>(text[at + k]);
    if ((next & 0xC0) != 0x80) return {};
    code = (code << 6) | (next & 0x3F);
  }
  const bool overlong = (length == 2 && code < 0x80) || (length == 3 && code < 0x800) ||
                        (length == 4 && code < 0x10000);
  if (overlong || code > 0x10FFFF || (code >= 0xD800 && code <= 0xDFFF)) return {};
  return {code, length};
}

}  // namespace arbiter::detail
