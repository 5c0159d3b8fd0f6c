// SPDX-License-Identifier: MIT
// SOFA files through libmysofa (sofa_hrtf.hpp).
#include "strike/audio/sofa_hrtf.hpp"

#include <mysofa.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace strike {
namespace {

struct SofaFree {
  void operator()(MYSOFA_HRTF* hrtf) const { mysofa_free(hrtf); }
};

std::string sofaError(int code) {
  switch (code) {
    case MYSOFA_INVALID_FORMAT: return "not a SOFA (HDF5) file";
    case MYSOFA_UNSUPPORTED_FORMAT: return "a SOFA file of a form libmysofa does not read";
    case MYSOFA_INVALID_ATTRIBUTES: return "its attributes are not those of SimpleFreeFieldHRIR";
    case MYSOFA_INVALID_DIMENSIONS: return "its dimensions are inconsistent";
    case MYSOFA_INVALID_DIMENSION_LIST: return "its dimension list is inconsistent";
    case MYSOFA_INVALID_COORDINATE_TYPE: return "a coordinate type libmysofa does not know";
    case MYSOFA_ONLY_EMITTER_WITH_ECI_SUPPORTED: return "more than one emitter";
    case MYSOFA_ONLY_DELAYS_WITH_IR_OR_MR_SUPPORTED: return "delays of an unsupported shape";
    case MYSOFA_ONLY_THE_SAME_SAMPLING_RATE_SUPPORTED: return "more than one sampling rate";
    case MYSOFA_RECEIVERS_WITH_RCI_SUPPORTED: return "receivers of an unsupported shape";
    case MYSOFA_RECEIVERS_WITH_CARTESIAN_SUPPORTED: return "receivers not in cartesian coordinates";
    case MYSOFA_INVALID_RECEIVER_POSITIONS: return "receivers not on the interaural axis";
    case MYSOFA_ONLY_SOURCES_WITH_MC_SUPPORTED: return "sources of an unsupported shape";
    case MYSOFA_NO_MEMORY: return "out of memory";
    case MYSOFA_READ_ERROR: return "cannot be read (missing, or not a readable file)";
    default: return "libmysofa error " + std::to_string(code);
  }
}

}  // namespace

Result<std::shared_ptr<const HrtfSet>> loadSofaHrtf(const std::string& path, double sample_rate_hz) {
  const std::string where = "--hrtf " + path + ": ";
  if (std::FILE* f = std::fopen(path.c_str(), "rb"))
    std::fclose(f);
  else
    return badInput(where + "cannot open it");
  int err = MYSOFA_OK;
  std::unique_ptr<MYSOFA_HRTF, SofaFree> sofa(mysofa_load(path.c_str(), &err));
  if (!sofa || err != MYSOFA_OK) return badInput(where + sofaError(err));
  if ((err = mysofa_check(sofa.get())) != MYSOFA_OK) return badInput(where + sofaError(err));
  MYSOFA_HRTF& h = *sofa;
  if (h.R != 2) return badInput(where + std::to_string(h.R) + " receivers (a binaural set has 2)");
  if (h.DataSamplingRate.elements < 1 || !(h.DataSamplingRate.values[0] > 0.0f))
    return badInput(where + "no sampling rate");
  if (h.DataSamplingRate.values[0] != static_cast<float>(sample_rate_hz) &&
      (err = mysofa_resample(sofa.get(), static_cast<float>(sample_rate_hz))) != MYSOFA_OK)
    return badInput(where + "cannot resample it to " + std::to_string(sample_rate_hz) + " Hz (" + sofaError(err) + ")");
  mysofa_tocartesian(sofa.get());
  // Which receiver is the left ear: the one further along +y (SOFA: y to the left).
  int left = 0;
  if (h.ReceiverPosition.elements >= 6 && h.ReceiverPosition.values[4] > h.ReceiverPosition.values[1]) left = 1;
  // Data.Delay (samples, per receiver or per measurement and receiver) as leading zeros.
  auto delayOf = [&](unsigned m, int r) -> unsigned {
    const unsigned count = h.DataDelay.elements;
    float d = 0.0f;
    if (count == 2)
      d = h.DataDelay.values[r];
    else if (count == 2 * h.M)
      d = h.DataDelay.values[2 * m + static_cast<unsigned>(r)];
    return std::isfinite(d) && d > 0.0f ? static_cast<unsigned>(std::lround(std::min(d, 4096.0f))) : 0u;
  };
  unsigned max_delay = 0;
  for (unsigned m = 0; m < h.M; ++m) max_delay = std::max({max_delay, delayOf(m, 0), delayOf(m, 1)});
  auto set = std::make_shared<HrtfSet>();
  set->sample_rate_hz = sample_rate_hz;
  set->taps = h.N + max_delay;
  set->directions.resize(h.M);
  set->left.assign(static_cast<size_t>(h.M) * set->taps, 0.0f);
  set->right.assign(static_cast<size_t>(h.M) * set->taps, 0.0f);
  for (unsigned m = 0; m < h.M; ++m) {
    for (int k = 0; k < 3; ++k) set->directions[m][k] = h.SourcePosition.values[3 * m + k];
    for (int r = 0; r < 2; ++r) {
      const float* ir = h.DataIR.values + (static_cast<size_t>(m) * 2 + static_cast<size_t>(r)) * h.N;
      std::vector<float>& out = r == left ? set->left : set->right;
      std::copy(ir, ir + h.N, out.begin() + static_cast<std::ptrdiff_t>(m * set->taps + delayOf(m, r)));
    }
  }
  if (const std::string why = prepareHrtfSet(*set); !why.empty()) return badInput(where + why);
  return std::shared_ptr<const HrtfSet>(std::move(set));
}

}  // namespace strike
