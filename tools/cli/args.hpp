// SPDX-License-Identifier: MIT
// A small, strict command-line parser: every option is declared with its help text, an unknown
// option or a malformed value is an error that names the option and the value (exit code 1).
#pragma once

#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "strike/audio/audio.hpp"
#include "strike/core/result.hpp"
#include "strike/synth/synth.hpp"

namespace strike::cli {

struct OptionSpec {
  std::string name;        ///< "--max-freq"
  std::string value_name;  ///< "HZ"; empty for a flag
  std::string help;        ///< one line; say the unit and the default
};

struct CommandSpec {
  std::string usage;    ///< "strike modes MESH -o BANK.modes [options]"
  std::string summary;  ///< what the command does, a few lines
  std::vector<OptionSpec> options;
  std::string examples;  ///< shown by --help
  int min_positional = 0, max_positional = 0;
};

class ParsedArgs {
 public:
  std::vector<std::string> positional;
  bool has(const std::string& name) const { return values_.count(name) > 0; }
  std::string text(const std::string& name, const std::string& fallback = "") const;
  /// A finite number; the error names the option and the value.
  Result<double> number(const std::string& name, double fallback) const;
  Result<long long> integer(const std::string& name, long long fallback) const;
  /// "X,Y,Z" as three finite numbers.
  Result<std::array<double, 3>> vector3(const std::string& name, std::array<double, 3> fallback) const;
  std::map<std::string, std::string> values_;
};

/// Parses argv (after the command name). `--help` is handled by the caller via wantsHelp.
Result<ParsedArgs> parseArgs(const CommandSpec& spec, const std::vector<std::string>& args);
bool wantsHelp(const std::vector<std::string>& args);
std::string helpText(const CommandSpec& spec);
/// Every --help line fits in this many columns: options' help is wrapped at word boundaries,
/// continuation lines under the first.
constexpr size_t kHelpWidth = 100;
/// `text` word-wrapped to `width` columns, its lines after the first indented by `indent`
/// (the first starts at column `indent`). The text's own line breaks are reflowed, so a source
/// line written a little longer or shorter never leaves a ragged line; a break is kept before an
/// empty line, a line that starts with a space (an indented list or example) or with "- ".
std::string wrapHelp(const std::string& text, size_t indent, size_t width);

/// The sample encoding from --format, defaulting by the output's extension: float for .wav
/// (keeps levels above full scale), pcm24 for .flac (FLAC has no float).
Result<SampleEncoding> sampleEncodingFor(const ParsedArgs& args, const std::string& output);

/// The synthesizer's kernel: --simd, else $STRIKE_SIMD, else auto (the widest the CPU has).
/// auto|scalar|avx2|avx512; a kernel the CPU lacks falls back to the next narrower one.
Result<SimdLevel> simdLevelFor(const ParsedArgs& args);

/// The --simd option's help row (render and hit).
inline constexpr const char* kSimdHelp =
    "synthesizer kernel: auto, scalar, avx2 or avx512; default $STRIKE_SIMD, else auto. Kernels differ "
    "only in the last bits (< -120 dB re peak: docs/determinism.md)";

/// The memory budget of a command's solves, bytes: --max-memory SIZE (K, M, G, T: powers of
/// 1024, as the cache's sizes), else the memory available now (MemAvailable; 0, no budget, when
/// it cannot be read).
Result<double> memoryBudgetFromArgs(const ParsedArgs& args);

/// The name in `names` the user most probably meant by `typed` (a slip of one or two letters:
/// "--rat" for "--rate", "rendr" for "render"), or "" when none is that close.
std::string closestName(const std::string& typed, const std::vector<std::string>& names);

/// Parses a number strictly: the whole text, finite. `what` names it in the error.
Result<double> parseNumber(const std::string& text, const std::string& what);

}  // namespace strike::cli
