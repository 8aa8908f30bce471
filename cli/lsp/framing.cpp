#include "lsp/framing.hpp"

#include <cctype>
#include <istream>
#include <ostream>

namespace arbiter::lsp {

namespace {

// Bodies beyond this are refused rather than allocated: no editor sends a config this large.
constexpr std::size_t kMaxBody = 64u << 20;

std::string lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

}  // namespace

std::optional<Frame> read_frame(std::istream& in, std::string* ended) {
  static const std::string kHeader = "content-length:";
  // Not an optional: GCC's -O3 takes its value for maybe uninitialised where it is read.
  std::size_t length = 0;
  bool has_length = false;
  std::string error;
  std::string skipped;
  std::string line;
  bool any = false;
  auto skip = [&](const std::string& bytes) {
    skipped +=
        (skipped.empty() ? "" : " ") + bytes.substr(0, 80) + (bytes.size() > 80 ? "..." : "");
  };
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) {
      if (!any) continue;  // stray blank lines between messages
      break;
    }
    // Bytes glued before a header (noise, or the rest of a body longer than its Content-Length
    // said): the message starts at the header.
    if (const auto at = lower(line).find(kHeader); at != std::string::npos && at > 0) {
      skip(line.substr(0, at));
      line.erase(0, at);
      has_length = false;
      error.clear();
    }
    const auto colon = line.find(':');
    if (colon == std::string::npos) {
      // Not a header: stray bytes, or the body of a message whose header was malformed.
      if (!has_length) skip(line);
      if (!has_length && !any) continue;
      error = "header line without ':': " + line.substr(0, 80);
      any = true;
      continue;
    }
    any = true;
    if (lower(line.substr(0, colon)) != "content-length") continue;
    const std::string value = line.substr(colon + 1);
    std::size_t parsed = 0;
    bool digits = false;
    bool valid = true;
    for (char c : value) {
      if (c == ' ' || c == '\t') continue;
      if (!std::isdigit(static_cast<unsigned char>(c)) || parsed > kMaxBody) {
        valid = false;
        break;
      }
      parsed = parsed * 10 + static_cast<std::size_t>(c - '0');
      digits = true;
    }
    if (!valid || !digits || parsed > kMaxBody) {
      error = "invalid Content-Length:" + value.substr(0, 80);
      has_length = false;
    } else {
      length = parsed;
      has_length = true;
    }
  }
  if (!any) return std::nullopt;
  if (!has_length) return Frame{{}, error.empty() ? "no Content-Length header" : error, skipped};
  Frame frame;
  frame.skipped = std::move(skipped);
  frame.body.resize(length);
  in.read(frame.body.data(), static_cast<std::streamsize>(length));
  if (static_cast<std::size_t>(in.gcount()) != length) {
    if (ended)
      *ended = "the input ended inside a message (" + std::to_string(in.gcount()) + " of " +
               std::to_string(length) + " bytes)";
    return std::nullopt;
  }
  return frame;
}

void write_frame(std::ostream& out, const std::string& body) {
  out << "Content-Length: " << body.size() << "\r\n\r\n" << body;
  out.flush();
}

}  // namespace arbiter::lsp
