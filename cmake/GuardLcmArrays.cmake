# cmake -DHEADERS="a.hpp;b.hpp" -P GuardLcmArrays.cmake
#
# lcm-gen's C++ decode() sizes each variable-length array from the count it
# has just read, before it checks that the bytes are there: a 110-byte
# message declaring 2e9 cells makes every reader allocate and zero 2 GB.
# Every element of an LCM array takes at least one byte on the wire, so a
# count above the bytes left (or below zero) cannot be a valid message.
# This inserts that check before each resize and fails the build if
# lcm-gen ever writes a resize this does not recognise.
foreach(header IN LISTS HEADERS)
  file(READ "${header}" text)
  string(REGEX REPLACE
    "\n([ ]*)this->([A-Za-z0-9_]+)\\.resize\\(this->([A-Za-z0-9_]+)\\);"
    "\n\\1if (this->\\3 < 0 || this->\\3 > maxlen - pos) return -1;  // ivoa: no allocation the bytes cannot fill\n\\1this->\\2.resize(this->\\3);"
    guarded "${text}")
  string(REGEX MATCHALL "\\.resize\\(" resizes "${guarded}")
  string(REGEX MATCHALL "ivoa: no allocation the bytes cannot fill" guards "${guarded}")
  list(LENGTH resizes resize_count)
  list(LENGTH guards guard_count)
  if(NOT resize_count EQUAL guard_count)
    message(FATAL_ERROR "${header}: ${resize_count} resizes in decode() but ${guard_count} guarded; "
                        "lcm-gen's output changed shape: update cmake/GuardLcmArrays.cmake")
  endif()
  file(WRITE "${header}" "${guarded}")
endforeach()
