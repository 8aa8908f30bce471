#pragma once
// Text in XML documents the CLI writes: the SVG of `arbiter plot`, the JUnit XML of `arbiter test`.

#include <string>
#include <string_view>

namespace arbiter::cli {

/// `text` as XML character data or an attribute value: the five markup characters escaped, and
/// what XML 1.0 cannot hold (invalid UTF-8, control characters but tab and line feed, U+FFFE and
/// U+FFFF) written as printable() writes it for a terminal (`\xff`, `\x01`, `\uffff`).
std::string xml_escaped(std::string_view text);

}  // namespace arbiter::cli
