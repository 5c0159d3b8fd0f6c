// SPDX-License-Identifier: MIT
// WAV/FLAC writing and reading through libsndfile (target strike_sndfile).
#include <sndfile.h>
#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>

#include "strike/core/atomic_file.hpp"  // temporaryPathFor
#include "strike/audio/audio.hpp"
#include "strike/core/interrupt_cleanup.hpp"

namespace strike {
namespace {

constexpr sf_count_t kChunkFrames = 1 << 14;

std::string lowerExtension(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

const char* encodingName(SampleEncoding encoding) {
  switch (encoding) {
    case SampleEncoding::Pcm16: return "16-bit PCM";
    case SampleEncoding::Pcm24: return "24-bit PCM";
    case SampleEncoding::Float32: return "32-bit float";
  }
  return "?";
}

/// Float to PCM held in the top bits of an int32 (libsndfile's int convention: PCM_16 takes
/// the top 16 bits, PCM_24 the top 24). Why not sf_writef_float: libsndfile scales float to PCM
/// by 0x7FFF but PCM to float by 1/0x8000, a gain mismatch of one LSB at full scale. Scaling by
/// 2^(bits-1) here makes a write/read round trip exact to half an LSB, and values beyond full
/// scale saturate (never wrap); NaN becomes 0.
int32_t toPcm(float x, int bits) {
  const double full_scale = std::ldexp(1.0, bits - 1);
  if (std::isnan(x)) return 0;
  double q = std::nearbyint(static_cast<double>(x) * full_scale);  // round half to even: deterministic
  q = std::clamp(q, -full_scale, full_scale - 1.0);
  return static_cast<int32_t>(q) * (int32_t{1} << (32 - bits));
}

}  // namespace

Status writeAudio(const std::string& path, const AudioBuffer& audio, SampleEncoding encoding) {
  const std::string ext = lowerExtension(path);
  int major = 0;
  if (ext == ".wav") {
    major = SF_FORMAT_WAV;
  } else if (ext == ".flac") {
    major = SF_FORMAT_FLAC;
  } else {
    return badInput(path + ": error: unsupported audio file extension '" + ext +
                    "'; supported extensions are .wav and .flac");
  }
  if (audio.channels < 1)
    return badInput(path + ": error: audio has " + std::to_string(audio.channels) + " channels, expected at least 1");
  if (audio.samples.size() % static_cast<size_t>(audio.channels) != 0)
    return badInput(path + ": error: " + std::to_string(audio.samples.size()) + " samples is not a whole number of " +
                    std::to_string(audio.channels) + "-channel frames");
  const double rate = audio.sample_rate_hz;
  if (!(rate >= 1.0 && rate <= 1e7) || rate != std::floor(rate))
    return badInput(path + ": error: sample rate " + std::to_string(rate) +
                    " Hz is not a positive whole number of hertz");
  int subtype = 0;
  int bits = 0;
  switch (encoding) {
    case SampleEncoding::Pcm16:
      subtype = SF_FORMAT_PCM_16;
      bits = 16;
      break;
    case SampleEncoding::Pcm24:
      subtype = SF_FORMAT_PCM_24;
      bits = 24;
      break;
    case SampleEncoding::Float32: subtype = SF_FORMAT_FLOAT; break;
  }
  if (major == SF_FORMAT_FLAC && encoding == SampleEncoding::Float32)
    return badInput(path +
                    ": error: FLAC stores integer PCM only; use 16- or 24-bit PCM, or a .wav file for 32-bit float");

  SF_INFO info{};
  info.samplerate = static_cast<int>(rate);
  info.channels = audio.channels;
  info.format = major | subtype;
  if (!sf_format_check(&info))
    return badInput(path + ": error: libsndfile cannot write " + std::string(encodingName(encoding)) + " " +
                    ext.substr(1) + " with " + std::to_string(audio.channels) + " channels at " +
                    std::to_string(info.samplerate) + " Hz");

  const std::string temp = temporaryPathFor(path);
  TemporaryRegistration registration(temp);  // removed if SIGINT/SIGTERM arrives mid-write
  SNDFILE* file = sf_open(temp.c_str(), SFM_WRITE, &info);
  if (!file) return badInput(path + ": error: cannot create output file: " + sf_strerror(nullptr));

  auto fail = [&](const std::string& what, SNDFILE* open_file) -> Status {
    const std::string message = path + ": error: " + what + ": " + sf_strerror(open_file);
    if (open_file) sf_close(open_file);
    std::remove(temp.c_str());
    return badInput(message);
  };

  // Why: a float WAV gets a PEAK chunk by default, and libsndfile stamps it with time(NULL),
  // which would make the same render give different bytes. Must be set before the first write.
  sf_command(file, SFC_SET_ADD_PEAK_CHUNK, nullptr, SF_FALSE);
  // Defensive: we convert to PCM ourselves (toPcm saturates), but if any float reaches a PCM
  // conversion inside libsndfile it must clip, not wrap.
  sf_command(file, SFC_SET_CLIPPING, nullptr, SF_TRUE);

  const auto channels = static_cast<size_t>(audio.channels);
  const auto total_frames = static_cast<sf_count_t>(audio.frames());
  std::vector<int32_t> pcm;
  if (bits > 0) pcm.resize(static_cast<size_t>(kChunkFrames) * channels);
  for (sf_count_t start = 0; start < total_frames; start += kChunkFrames) {
    const sf_count_t count = std::min(kChunkFrames, total_frames - start);
    const float* src = audio.samples.data() + static_cast<size_t>(start) * channels;
    sf_count_t written = 0;
    if (bits > 0) {
      const size_t n = static_cast<size_t>(count) * channels;
      for (size_t i = 0; i < n; ++i) pcm[i] = toPcm(src[i], bits);
      written = sf_writef_int(file, pcm.data(), count);
    } else {
      written = sf_writef_float(file, src, count);
    }
    if (written != count) return fail("writing failed", file);
  }
  sf_write_sync(file);
  // sf_close rewrites the header and reports delayed write errors (a full disk).
  const int close_error = sf_close(file);
  if (close_error != SF_ERR_NO_ERROR) {
    const std::string message = path + ": error: closing failed: " + sf_error_number(close_error);
    std::remove(temp.c_str());
    return badInput(message);
  }
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    const int rename_errno = errno;
    std::remove(temp.c_str());
    return badInput(path + ": error: cannot move the output into place: " + std::strerror(rename_errno));
  }
  return {};
}

Result<AudioBuffer> readAudio(const std::string& path) {
  struct stat st {};
  if (stat(path.c_str(), &st) != 0) return badInput(path + ": error: cannot open: " + std::strerror(errno));
  if (S_ISDIR(st.st_mode)) return badInput(path + ": error: is a directory, expected an audio file");
  SF_INFO info{};
  SNDFILE* file = sf_open(path.c_str(), SFM_READ, &info);
  if (!file) return badInput(path + ": error: cannot read audio: " + sf_strerror(nullptr));
  if (info.channels < 1 || info.samplerate < 1) {
    sf_close(file);
    return badInput(path + ": error: invalid header: " + std::to_string(info.channels) + " channels at " +
                    std::to_string(info.samplerate) + " Hz");
  }
  AudioBuffer audio;
  audio.sample_rate_hz = info.samplerate;
  audio.channels = info.channels;
  const auto channels = static_cast<size_t>(info.channels);
  // Reserve from the header only when it is plausible; pipes and some formats report huge counts.
  if (info.frames > 0 && info.frames < (sf_count_t{1} << 31) / info.channels)
    audio.samples.reserve(static_cast<size_t>(info.frames) * channels);
  std::vector<float> chunk(static_cast<size_t>(kChunkFrames) * channels);
  for (;;) {
    const sf_count_t got = sf_readf_float(file, chunk.data(), kChunkFrames);
    if (got <= 0) break;
    audio.samples.insert(audio.samples.end(), chunk.begin(),
                         chunk.begin() + static_cast<ptrdiff_t>(got * info.channels));
  }
  const int read_error = sf_error(file);
  if (read_error != SF_ERR_NO_ERROR) {
    const std::string message = path + ": error: reading failed: " + sf_strerror(file);
    sf_close(file);
    return badInput(message);
  }
  sf_close(file);
  return audio;
}

}  // namespace strike
