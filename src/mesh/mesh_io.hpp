// SPDX-License-Identifier: MIT
// Private helpers shared by the mesh readers (not a public header): whole-file reading with
// clear errors, a tokenizer that remembers line numbers, strict number parsing, and the
// project's error message format ("path:line: error: what, got value, expected range").
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "strike/mesh/mesh.hpp"
#include "strike/core/result.hpp"

namespace strike::detail {

/// Largest mesh file we read into memory. Far above any mesh the FEM could solve, and keeps a
/// hostile path (e.g. /dev/zero) from exhausting memory.
constexpr uint64_t kMaxMeshFileBytes = uint64_t{4} << 30;

/// Reads a whole mesh file: strike::readWholeFile (read_file.hpp) capped at kMaxMeshFileBytes,
/// after refusing anything but a regular file (a device like /dev/zero reports size 0).
Result<std::string> readWholeFile(const std::string& path);

/// Lower-cased extension including the dot (".obj"), or "" when there is none.
std::string lowerExtension(const std::string& path);

/// Shortened, printable copy of a token for error messages (binary garbage stays readable).
std::string quoteToken(std::string_view token);

/// "path:line: error: " prefix.
std::string at(const std::string& path, int64_t line);

/// Strict number parsing: the whole token must be the number.
bool parseDouble(std::string_view token, double& value);
bool parseInt64(std::string_view token, int64_t& value);

/// Splits text into whitespace-separated tokens and tracks the line of each. '#'-comments can be
/// enabled (TetGen files). Never reads past the end of the text.
class Tokenizer {
 public:
  Tokenizer(std::string_view text, bool hash_comments) : text_(text), hash_comments_(hash_comments) {}

  /// Next token, or an empty view at the end of the text. line() is the token's line.
  std::string_view next();
  /// Next token only if it is on the current line (the line of the last token returned).
  std::string_view nextOnLine();
  /// Skips the rest of the current line.
  void skipLine();
  /// Line of the last token returned (1-based).
  int64_t line() const { return token_line_; }
  /// Bytes not yet consumed (an upper bound on what the rest of the file can hold).
  size_t remainingBytes() const { return text_.size() - pos_; }
  bool atEnd();

 private:
  void skipSpace(bool stop_at_newline);
  std::string_view text_;
  bool hash_comments_;
  size_t pos_ = 0;
  int64_t line_ = 1;
  int64_t token_line_ = 1;
};

}  // namespace strike::detail
