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

std::optional<Frame> read_frame(std::istream& in) {
  std::optional<std::size_t> length;
  std::string error;
  std::string line;
  bool any = false;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) {
      if (!any) continue;  // stray blank lines between messages
      break;
    }
    any = true;
    const auto colon = line.find(':');
    if (colon == std::string::npos) {
      error = "header line without ':': " + line;
      continue;
    }
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
      error = "invalid Content-Length:" + value;
    } else {
      length = parsed;
    }
  }
  if (!any) return std::nullopt;
  if (!length) return Frame{{}, error.empty() ? "no Content-Length header" : error};
  Frame frame;
  frame.body.resize(*length);
  in.read(frame.body.data(), static_cast<std::streamsize>(*length));
  if (static_cast<std::size_t>(in.gcount()) != *length) return std::nullopt;
  return frame;
}

void write_frame(std::ostream& out, const std::string& body) {
  out << "Content-Length: " << body.size() << "\r\n\r\n" << body;
  out.flush();
}

}  // namespace arbiter::lsp
