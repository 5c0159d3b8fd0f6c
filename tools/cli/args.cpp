// SPDX-License-Identifier: MIT
#include "args.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

#include "strike/core/parse_size.hpp"

namespace strike::cli {

Result<double> parseNumber(const std::string& text, const std::string& what) {
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(begin, &end);
  if (text.empty() || end != begin + text.size()) return badInput(what + " = '" + text + "' (expected a number)");
  if (!std::isfinite(value) || errno == ERANGE) return badInput(what + " = '" + text + "' (must be finite)");
  return value;
}

Result<SampleEncoding> sampleEncodingFor(const ParsedArgs& args, const std::string& output) {
  const bool flac = output.size() >= 5 && output.compare(output.size() - 5, 5, ".flac") == 0;
  const std::string format = args.text("--format", flac ? "pcm24" : "float");
  if (format == "pcm16") return SampleEncoding::Pcm16;
  if (format == "pcm24") return SampleEncoding::Pcm24;
  if (format == "float") {
    // Refused here, before any work, not by the writer after it (FLAC has no float samples).
    if (flac)
      return badInput("--format float with " + output +
                      ": FLAC stores integer PCM only; use pcm16 or pcm24, or a .wav file");
    return SampleEncoding::Float32;
  }
  return badInput("--format = '" + format + "' (expected pcm16, pcm24 or float)");
}

Result<SimdLevel> simdLevelFor(const ParsedArgs& args) {
  const char* env = std::getenv("STRIKE_SIMD");
  const bool from_option = args.has("--simd");
  const std::string name = from_option ? args.text("--simd") : (env != nullptr ? env : "auto");
  if (name == "auto" || name.empty()) return SimdLevel::Auto;
  if (name == "scalar") return SimdLevel::Scalar;
  if (name == "avx2") return SimdLevel::Avx2;
  if (name == "avx512") return SimdLevel::Avx512;
  return badInput(std::string(from_option ? "--simd" : "STRIKE_SIMD") + " = '" + name +
                  "' (expected auto, scalar, avx2 or avx512)");
}

std::string ParsedArgs::text(const std::string& name, const std::string& fallback) const {
  auto it = values_.find(name);
  return it == values_.end() ? fallback : it->second;
}

Result<double> ParsedArgs::number(const std::string& name, double fallback) const {
  if (!has(name)) return fallback;
  return parseNumber(text(name), name);
}

Result<long long> ParsedArgs::integer(const std::string& name, long long fallback) const {
  if (!has(name)) return fallback;
  const std::string value = text(name);
  char* end = nullptr;
  errno = 0;
  const long long parsed = std::strtoll(value.c_str(), &end, 10);
  if (value.empty() || end != value.c_str() + value.size() || errno == ERANGE)
    return badInput(name + " = '" + value + "' (expected a whole number)");
  return parsed;
}

Result<std::array<double, 3>> ParsedArgs::vector3(const std::string& name, std::array<double, 3> fallback) const {
  if (!has(name)) return fallback;
  const std::string value = text(name);
  std::array<double, 3> out{};
  std::stringstream parts(value);
  std::string part;
  int count = 0;
  while (std::getline(parts, part, ',')) {
    if (count == 3) return badInput(name + " = '" + value + "' (expected three numbers X,Y,Z)");
    Result<double> number = parseNumber(part, name);
    if (!number) return badInput(name + " = '" + value + "' (expected three finite numbers X,Y,Z)");
    out[count++] = *number;
  }
  if (count != 3) return badInput(name + " = '" + value + "' (expected three numbers X,Y,Z)");
  return out;
}

bool wantsHelp(const std::vector<std::string>& args) {
  for (const std::string& a : args)
    if (a == "--help" || a == "-h") return true;
  return false;
}

Result<ParsedArgs> parseArgs(const CommandSpec& spec, const std::vector<std::string>& args) {
  ParsedArgs parsed;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (arg.size() > 1 && arg[0] == '-' &&
        !(arg.size() > 1 && (std::isdigit(static_cast<unsigned char>(arg[1])) || arg[1] == '.'))) {
      std::string name = arg, value;
      bool has_inline_value = false;
      if (const size_t eq = arg.find('='); eq != std::string::npos) {
        name = arg.substr(0, eq);
        value = arg.substr(eq + 1);
        has_inline_value = true;
      }
      const OptionSpec* option = nullptr;
      for (const OptionSpec& o : spec.options)
        if (o.name == name) option = &o;
      if (!option) {
        std::vector<std::string> names;
        for (const OptionSpec& o : spec.options) names.push_back(o.name);
        const std::string near = closestName(name, names);
        return badInput("unknown option '" + name + "'" + (near.empty() ? "" : "; did you mean " + near + "?") +
                        " (see `" + spec.usage.substr(0, spec.usage.find(' ', 7)) + " --help`)");
      }
      if (option->value_name.empty()) {
        if (has_inline_value) return badInput("option " + name + " takes no value");
        parsed.values_[name] = "1";
        continue;
      }
      if (!has_inline_value) {
        if (i + 1 >= args.size()) return badInput("option " + name + " needs a value " + option->value_name);
        value = args[++i];
      }
      if (parsed.values_.count(name)) return badInput("option " + name + " given twice");
      parsed.values_[name] = value;
    } else {
      parsed.positional.push_back(arg);
    }
  }
  const int count = static_cast<int>(parsed.positional.size());
  if (count < spec.min_positional) return badInput("missing argument; usage: " + spec.usage);
  if (count > spec.max_positional)
    return badInput("unexpected argument '" + parsed.positional[spec.max_positional] + "'; usage: " + spec.usage);
  return parsed;
}

std::string closestName(const std::string& typed, const std::vector<std::string>& names) {
  // Levenshtein distance by one row of the table (Wagner & Fischer 1974).
  auto distance = [](const std::string& a, const std::string& b) {
    std::vector<size_t> row(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
      size_t diagonal = row[0];
      row[0] = i;
      for (size_t j = 1; j <= b.size(); ++j) {
        const size_t above = row[j];
        row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
        diagonal = above;
      }
    }
    return row[b.size()];
  };
  std::string best;
  size_t best_distance = 0;
  for (const std::string& name : names) {
    const size_t d = distance(typed, name);
    if (best.empty() || d < best_distance) best = name, best_distance = d;
  }
  // Close enough to be a slip: at most 2 edits, and about a third of the letters at most.
  const size_t letters =
      typed.find_first_not_of('-') == std::string::npos ? 0 : typed.size() - typed.find_first_not_of('-');
  if (best.empty() || best_distance > 2 || 3 * best_distance > std::max<size_t>(letters, 3) + 1) return "";
  return best;
}

std::string wrapHelp(const std::string& text, size_t indent, size_t width) {
  std::string out;
  size_t column = indent;
  std::istringstream lines(text);
  std::string line;
  bool first_line = true, previous_empty = false;
  while (std::getline(lines, line)) {
    const bool keeps_break = line.empty() || previous_empty || line[0] == ' ' || line.rfind("- ", 0) == 0;
    if (!first_line && keeps_break) out += "\n" + std::string(indent, ' '), column = indent;
    // A reflowed line continues the previous one's words (the word loop adds the space).
    bool first_word = first_line || keeps_break;
    first_line = false;
    previous_empty = line.empty();
    std::istringstream words(line);
    std::string word;
    while (words >> word) {
      if (!first_word && column + 1 + word.size() > width) {
        out += "\n" + std::string(indent, ' ');
        column = indent;
        first_word = true;
      }
      if (!first_word) out += ' ', ++column;
      out += word;
      column += word.size();
      first_word = false;
    }
  }
  return out;
}

std::string helpText(const CommandSpec& spec) {
  std::ostringstream out;
  out << "usage: " << spec.usage << "\n\n" << wrapHelp(spec.summary, 0, kHelpWidth) << "\n";
  if (!spec.options.empty()) {
    out << "\noptions:\n";
    for (const OptionSpec& o : spec.options) {
      std::string left = "  " + o.name + (o.value_name.empty() ? "" : " " + o.value_name);
      if (left.size() < 30)
        left.resize(30, ' ');
      else
        left += "\n" + std::string(30, ' ');
      out << left << wrapHelp(o.help, 30, kHelpWidth) << "\n";
    }
  }
  if (!spec.examples.empty()) out << "\nexamples:\n" << spec.examples;
  out << "\nEvery command, option, output and exit code: docs/cli.md; the scene file: docs/scene-format.md\n"
         "(in the source tree; exit codes: 0 success, 1 bad input, 2 internal error).\n";
  return out.str();
}

namespace {

/// MemAvailable from /proc/meminfo, bytes; 0 when it cannot be read.
double availableMemoryBytes() {
  std::FILE* file = std::fopen("/proc/meminfo", "r");
  if (!file) return 0.0;
  char line[256];
  double bytes = 0.0;
  while (std::fgets(line, sizeof line, file)) {
    unsigned long long kib = 0;
    if (std::sscanf(line, "MemAvailable: %llu kB", &kib) == 1) {
      bytes = 1024.0 * static_cast<double>(kib);
      break;
    }
  }
  std::fclose(file);
  return bytes;
}

}  // namespace

Result<double> memoryBudgetFromArgs(const ParsedArgs& args) {
  if (!args.has("--max-memory")) return availableMemoryBytes();
  Result<uint64_t> bytes = parseByteSize(args.text("--max-memory"), "--max-memory");
  if (!bytes) return bytes.error();
  if (*bytes == 0) return badInput("--max-memory = " + args.text("--max-memory") + " (must be > 0, e.g. 4G or 500M)");
  return static_cast<double>(*bytes);
}

}  // namespace strike::cli
