#include "commands/xml.hpp"

#include "arbiter/diagnostics.hpp"

namespace arbiter::cli {

std::string xml_escaped(std::string_view text) {
  // XML 1.0 holds UTF-8 and no control characters but tab and line breaks: a file name or an
  // event's text may have either, shown as the terminal shows them (\xff).
  const std::string shown = printable(text, true);
  std::string out;
  for (std::size_t i = 0; i < shown.size(); ++i) {
    const char c = shown[i];
    // U+FFFE and U+FFFF are no XML characters either.
    if (c == '\xEF' && i + 2 < shown.size() && shown[i + 1] == '\xBF' &&
        (shown[i + 2] == '\xBE' || shown[i + 2] == '\xBF')) {
      out += shown[i + 2] == '\xBE' ? "\\ufffe" : "\\uffff";
      i += 2;
      continue;
    }
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

}  // namespace arbiter::cli
