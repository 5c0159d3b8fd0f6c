// SPDX-License-Identifier: MIT
// Every documented order of create and destroy (strike.h: banks may be destroyed before or after
// their context; objects keep their bank's data alive), each with a counting allocator: after the
// last destroy every allocation made through the callback has been freed, and a bank whose handle
// is gone still sounds through the objects that use it. Under ASan (the asan build) a read of
// freed memory in any order fails too.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "check.hpp"
#include "struck_bank.hpp"

namespace {

using strike::runtime_test::bankBytes;

struct AllocationCount {
  long live = 0;
  long total = 0;
};

void* STRIKE_CALL countingAlloc(void* user, size_t size, size_t alignment) {
  auto* count = static_cast<AllocationCount*>(user);
  // aligned_alloc wants a size that is a multiple of the alignment.
  const size_t rounded = (size + alignment - 1) / alignment * alignment;
  void* p = std::aligned_alloc(alignment, rounded);
  if (p) ++count->live, ++count->total;
  return p;
}

void STRIKE_CALL countingFree(void* user, void* pointer) {
  if (!pointer) return;
  --static_cast<AllocationCount*>(user)->live;
  std::free(pointer);
}

const std::vector<uint8_t>& bytes() {
  static const std::vector<uint8_t> b = bankBytes({440.0, 1000.0}, 1e-9, 4.0);
  return b;
}

strike_context makeContext(AllocationCount& count) {
  strike_context_config config = strike_context_config_default();
  config.channels = 1;
  config.max_block_frames = 512;
  config.alloc = countingAlloc;
  config.free = countingFree;
  config.user = &count;
  strike_context context = nullptr;
  CHECK_OK(strike_context_create(&config, &context));
  return context;
}

strike_bank loadBank(strike_context context) {
  strike_bank bank = nullptr;
  CHECK_OK(strike_bank_load_memory(context, bytes().data(), bytes().size(), &bank));
  return bank;
}

strike_object_id addObject(strike_context context, strike_bank bank) {
  strike_object_config config = strike_object_config_default();
  config.bank = bank;
  config.position[1] = 1.0;
  strike_object_id object{};
  CHECK_OK(strike_object_add(context, &config, &object));
  return object;
}

/// Strikes `object` and renders 512 frames; the block's energy.
double strikeAndRender(strike_context context, strike_object_id object) {
  strike_impact_desc hit = strike_impact_desc_default();
  hit.object = object;
  hit.surface_vertex = 4;
  hit.impulse[2] = 1e-2;
  hit.normal_speed_m_s = 1.0;
  CHECK_OK(strike_impact(context, &hit));
  std::vector<float> block(512);
  float* out[1] = {block.data()};
  CHECK_OK(strike_render(context, out, 1, 512));
  double energy = 0.0;
  for (float x : block) energy += static_cast<double>(x) * x;
  return energy;
}

void tidyOrder() {  // remove the object, destroy the bank, then the context
  AllocationCount count;
  strike_context context = makeContext(count);
  strike_bank bank = loadBank(context);
  const strike_object_id object = addObject(context, bank);
  CHECK(strikeAndRender(context, object) > 0.0);
  CHECK_OK(strike_object_remove(context, object));
  CHECK_OK(strike_context_collect(context));
  CHECK(strike_object_is_valid(context, object) == 0);
  CHECK_STATUS(strike_object_remove(context, object), STRIKE_ERR_STALE_ID);
  strike_bank_destroy(bank);
  strike_context_destroy(context);
  CHECK(count.total > 0);  // the callback was used at all
  CHECK(count.live == 0);
}

void bankHandleDestroyedWhileItsObjectSounds() {
  AllocationCount count;
  strike_context context = makeContext(count);
  strike_bank bank = loadBank(context);
  const strike_object_id object = addObject(context, bank);
  strike_bank_destroy(bank);  // the object keeps the bank's data alive
  CHECK(strike_object_is_valid(context, object) == 1);
  CHECK(strikeAndRender(context, object) > 0.0);
  CHECK_OK(strike_object_remove(context, object));
  strike_context_destroy(context);
  CHECK(count.live == 0);
}

void contextDestroyedWithObjectsThenBank() {  // a bank outliving its context
  AllocationCount count;
  strike_context context = makeContext(count);
  strike_bank bank = loadBank(context);
  const strike_object_id object = addObject(context, bank);
  CHECK(strikeAndRender(context, object) > 0.0);
  strike_context_destroy(context);  // object still in it, bank handle still held
  strike_bank_info info{};
  info.struct_size = sizeof info;
  CHECK_OK(strike_bank_get_info(bank, &info));  // the bank is usable on its own
  CHECK(info.mode_count == 2);
  strike_bank_destroy(bank);
  CHECK(count.live == 0);
}

void contextDestroyedBeforeAnyObject() {
  AllocationCount count;
  strike_context context = makeContext(count);
  strike_bank first = loadBank(context), second = loadBank(context);
  strike_context_destroy(context);
  strike_bank_destroy(second);  // in the reverse order of loading
  strike_bank_destroy(first);
  CHECK(count.live == 0);
}

void bankDestroyedRightAfterLoading() {
  AllocationCount count;
  strike_context context = makeContext(count);
  strike_bank_destroy(loadBank(context));
  strike_context_destroy(context);
  CHECK(count.live == 0);
}

void nullHandlesAreNoOps() {
  strike_bank_destroy(nullptr);
  strike_context_destroy(nullptr);
}

}  // namespace

int main() {
  tidyOrder();
  bankHandleDestroyedWhileItsObjectSounds();
  contextDestroyedWithObjectsThenBank();
  contextDestroyedBeforeAnyObject();
  bankDestroyedRightAfterLoading();
  nullHandlesAreNoOps();
  return strike::check::checkExitCode("lifecycle_test");
}
