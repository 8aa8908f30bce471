#pragma once
// The base protocol of the Language Server Protocol: messages framed by a `Content-Length`
// header over a byte stream (the server's stdin and stdout).

#include <iosfwd>
#include <optional>
#include <string>

namespace arbiter::lsp {

/// One message read from the stream.
struct Frame {
  std::string body;     ///< the message's JSON text
  std::string error;    ///< non-empty: the header was malformed (the body is empty)
  std::string skipped;  ///< non-empty: what was dropped before this message's header, for the log
};

/// Reads the next message; nullopt at the end of the stream (`ended` then says whether it ended
/// inside a message). A header without a valid Content-Length is returned as an error (its block
/// is skipped) so that the caller can answer. Stray bytes between messages, or a malformed
/// message's body, are skipped up to the next `Content-Length:` header, so that the stream
/// recovers at the next well-formed message.
std::optional<Frame> read_frame(std::istream& in, std::string* ended = nullptr);

/// Writes `body` with its header and flushes.
void write_frame(std::ostream& out, const std::string& body);

}  // namespace arbiter::lsp
