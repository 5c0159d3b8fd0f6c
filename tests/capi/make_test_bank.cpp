// SPDX-License-Identifier: MIT
// Writes the hand-made test bank (test_bank.hpp) to argv[1], for the plain C test.
#include <cstdio>

#include "test_bank.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUT.modes\n", argv[0]);
    return 1;
  }
  const strike::Status s = strike::writeBank(argv[1], strike::test::makeTestBank());
  if (!s) {
    std::fprintf(stderr, "%s\n", s.error().message.c_str());
    return 1;
  }
  return 0;
}
