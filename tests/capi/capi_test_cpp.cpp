// SPDX-License-Identifier: MIT
// The plain C API test compiled as C++17: strike.h must be valid C++ too.
#include "capi_test.c"
