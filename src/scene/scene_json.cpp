// SPDX-License-Identifier: MIT
// The scene's JSON read strictly (target strike_scene_file): the text into a json value with
// every error at its line and column, and typed values whose messages name the key path
// ("objects[2].velocity[1]") and the value.
#include <cctype>
#include <cmath>
#include <cstring>
#include <optional>

#include "scene_json.hpp"

namespace strike::detail {
namespace {

constexpr int kMaxNestingDepth = 64;  // a scene is shallow; deeper input is hostile

/// Line and column of a byte offset, for JSON syntax errors.
std::string lineColumn(const std::string& text, size_t offset) {
  size_t line = 1, column = 1;
  for (size_t i = 0; i < offset && i < text.size(); ++i) {
    if (text[i] == '\n')
      ++line, column = 1;
    else
      ++column;
  }
  return std::to_string(line) + ":" + std::to_string(column);
}

/// Rejects nesting deeper than kMaxNestingDepth before the recursive parser sees it.
std::optional<size_t> tooDeepAt(const std::string& text) {
  int depth = 0;
  bool in_string = false, escaped = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '{' || c == '[') {
      if (++depth > kMaxNestingDepth) return i;
    } else if (c == '}' || c == ']') {
      --depth;
    }
  }
  return std::nullopt;
}
}  // namespace

std::string show(const json& value) {
  std::string text = value.dump();
  if (text.size() > 60) text = text.substr(0, 57) + "...";
  return text;
}
Result<json> readJson(const std::string& json_text, const std::string& path) {
  if (std::optional<size_t> at = tooDeepAt(json_text))
    return badInput(path + ":" + lineColumn(json_text, *at) + ": error: JSON nested deeper than " +
                    std::to_string(kMaxNestingDepth) + " levels");
  json doc = json::parse(json_text, nullptr, /*allow_exceptions=*/false);
  if (doc.is_discarded()) {
    // Re-parse with exceptions only to learn where it failed (the message has the byte offset).
    try {
      const json unused = json::parse(json_text);
      (void)unused;
    } catch (const json::parse_error& e) {
      return badInput(path + ":" + lineColumn(json_text, e.byte > 0 ? e.byte - 1 : 0) +
                      ": error: invalid JSON: " + std::string(e.what()).substr(std::string(e.what()).find(':') + 2));
    } catch (const json::exception& e) {  // e.g. a number too large for a double
      // The library does not say where: find the number it names ("... parsing '1e999'") as a
      // value of its own in the text.
      const std::string what = std::string(e.what()).substr(std::string(e.what()).find(']') + 2);
      std::string where;
      const size_t open = what.find('\''), close = what.rfind('\'');
      if (open != std::string::npos && close > open + 1) {
        const std::string number = what.substr(open + 1, close - open - 1);
        auto partOfNumber = [](char c) {
          return std::isdigit(static_cast<unsigned char>(c)) || std::strchr(".eE+-", c);
        };
        for (size_t at = json_text.find(number); at != std::string::npos; at = json_text.find(number, at + 1)) {
          const bool starts = at == 0 || !partOfNumber(json_text[at - 1]) || json_text[at - 1] == '-';
          const size_t end = at + number.size();
          if (starts && (end == json_text.size() || !partOfNumber(json_text[end]))) {
            where = ":" + lineColumn(json_text, at);
            break;
          }
        }
      }
      return badInput(path + where + ": error: invalid JSON: " + what +
                      (what.find("overflow") != std::string::npos ? " (larger than any double, ~1.8e308)" : ""));
    }
    return badInput(path + ": error: invalid JSON");
  }
  return doc;
}

const std::vector<const char*>& keysOf(const char* where) {
  for (const SceneKeyTable& table : sceneKeyTables())
    if (std::string(table.where) == where) return table.keys;
  static const std::vector<const char*> none;
  return none;
}

Status checkKeys(const json& object, const Where& where, const std::vector<const char*>& known) {
  if (!object.is_object()) return where.error("expected an object, got " + show(object));
  for (const auto& item : object.items()) {
    bool found = false;
    for (const char* k : known) found = found || item.key() == k;
    if (!found) {
      std::string list;
      for (const char* k : known) list += std::string(list.empty() ? "" : ", ") + k;
      return where.at(item.key()).error("unknown key (known keys here: " + list + ")");
    }
  }
  return {};
}

Result<double> number(const json& value, const Where& where) {
  if (!value.is_number()) return where.error("expected a number, got " + show(value));
  const double x = value.get<double>();
  if (!std::isfinite(x)) return where.error("expected a finite number, got " + show(value));
  return x;
}

/// [w, x, y, z] within 0.001 of unit length, normalized.
Result<std::array<double, 4>> unitQuaternion(const json& value, const Where& where) {
  Result<std::array<double, 4>> q = vector<4>(value, where);
  if (!q) return q.error();
  const double norm = std::sqrt((*q)[0] * (*q)[0] + (*q)[1] * (*q)[1] + (*q)[2] * (*q)[2] + (*q)[3] * (*q)[3]);
  if (std::fabs(norm - 1.0) > 1e-3)
    return where.error("expected a unit quaternion [w, x, y, z], got " + show(value) + " (norm " +
                       std::to_string(norm) + ")");
  std::array<double, 4> unit{};
  for (int i = 0; i < 4; ++i) unit[i] = (*q)[i] / norm;
  return unit;
}

Result<std::string> text(const json& value, const Where& where) {
  if (!value.is_string()) return where.error("expected a string, got " + show(value));
  return value.get<std::string>();
}
}  // namespace strike::detail
