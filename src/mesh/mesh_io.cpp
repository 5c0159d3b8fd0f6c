// SPDX-License-Identifier: MIT
#include "mesh_io.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <system_error>

#include "strike/core/read_file.hpp"

namespace strike::detail {

Result<std::string> readWholeFile(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec || !fs::exists(status)) return badInput(path + ": error: mesh file not found");
  if (fs::is_directory(status)) return badInput(path + ": error: is a directory, expected a mesh file");
  if (!fs::is_regular_file(status)) return badInput(path + ": error: not a regular file, expected a mesh file");
  return strike::readWholeFile(path, kMaxMeshFileBytes);
}

std::string lowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

std::string quoteToken(std::string_view token) {
  constexpr size_t kMax = 40;
  std::string out = "\"";
  for (size_t i = 0; i < token.size() && i < kMax; ++i) {
    const unsigned char c = static_cast<unsigned char>(token[i]);
    if (std::isprint(c)) {
      out += static_cast<char>(c);
    } else {
      static const char* kHex = "0123456789abcdef";
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  if (token.size() > kMax) out += "...";
  out += '"';
  return out;
}

std::string at(const std::string& path, int64_t line) { return path + ":" + std::to_string(line) + ": error: "; }

bool parseDouble(std::string_view token, double& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, value);
  // Out-of-range (1e999) is reported as not finite by the caller's check.
  if (ec == std::errc::result_out_of_range && ptr == end) {
    value = token.front() == '-' ? -HUGE_VAL : HUGE_VAL;
    return true;
  }
  return ec == std::errc() && ptr == end;
}

bool parseInt64(std::string_view token, int64_t& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, value);
  return ec == std::errc() && ptr == end;
}

void Tokenizer::skipSpace(bool stop_at_newline) {
  while (pos_ < text_.size()) {
    const char c = text_[pos_];
    if (c == '\n') {
      if (stop_at_newline) return;
      ++line_;
      ++pos_;
    } else if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
      ++pos_;
    } else if (hash_comments_ && c == '#') {
      while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
    } else {
      return;
    }
  }
}

std::string_view Tokenizer::next() {
  skipSpace(false);
  token_line_ = line_;
  const size_t start = pos_;
  while (pos_ < text_.size()) {
    const char c = text_[pos_];
    if (c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v') break;
    if (hash_comments_ && c == '#') break;
    ++pos_;
  }
  return text_.substr(start, pos_ - start);
}

std::string_view Tokenizer::nextOnLine() {
  skipSpace(true);
  if (pos_ >= text_.size() || text_[pos_] == '\n') return {};
  return next();
}

void Tokenizer::skipLine() {
  while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
}

bool Tokenizer::atEnd() {
  skipSpace(false);
  return pos_ >= text_.size();
}

}  // namespace strike::detail
