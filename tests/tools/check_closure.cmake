# SPDX-License-Identifier: MIT
# cmake -DCLOSURE="a b c" -DMUST=name -DMUST_NOT=regex -P check_closure.cmake
# Fails when the link closure (link_closure.cmake, space-separated) lacks MUST or has an entry
# matching MUST_NOT.
cmake_minimum_required(VERSION 3.22)  # IN_LIST
string(REPLACE " " ";" entries "${CLOSURE}")
if(NOT MUST IN_LIST entries)
  message(FATAL_ERROR "the link closure lacks ${MUST} (the walk stopped early?): ${CLOSURE}")
endif()
foreach(entry IN LISTS entries)
  if(entry MATCHES "${MUST_NOT}")
    message(FATAL_ERROR "the link closure has ${entry}, which it must not: ${CLOSURE}")
  endif()
endforeach()
message(STATUS "link closure (${MUST}, nothing matching ${MUST_NOT}): ${CLOSURE}")
