#pragma once
// Text in XML documents the CLI writes: the SVG of `arbiter plot`, the JUnit XML of `arbiter test`.

#include <string>
#include <string_view>

namespace arbiter::cli {

/// `text` as XML character data or an attribute value: the five markup characters escaped, and
/// the control characters XML 1.0 does not allow (all but tab and line breaks) left out.
std::string xml_escaped(std::string_view text);

}  // namespace arbiter::cli
