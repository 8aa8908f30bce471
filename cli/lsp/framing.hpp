#pragma once
// The base protocol of the Language Server Protocol: messages framed by a `Content-Length`
// header over a byte stream (the server's stdin and stdout).

#include <iosfwd>
#include <optional>
#include <string>

namespace arbiter::lsp {

/// One message read from the stream.
struct Frame {
  std::string body;   ///< the message's JSON text
  std::string error;  ///< non-empty: the header was malformed (the body is empty)
};

/// Reads the next message; nullopt at the end of the stream. A header without a valid
/// Content-Length is returned as an error (its block is skipped) so that the caller can answer.
std::optional<Frame> read_frame(std::istream& in);

/// Writes `body` with its header and flushes.
void write_frame(std::ostream& out, const std::string& body);

}  // namespace arbiter::lsp
