// Calls tune_libtorch_runtime() as the LibTorch programs do, then prints the
// two variables it sets, for the tests in CMakeLists.txt to match.
#include <cstdlib>
#include <iostream>

#include "ivoa/introspection/model.hpp"

int main(int, char** argv) {
  ivoa::introspection::tune_libtorch_runtime(argv);
  for (const char* name : {"OMP_WAIT_POLICY", "GLIBC_TUNABLES"}) {
    const char* value = std::getenv(name);
    std::cout << name << '=' << (value ? value : "(unset)") << '\n';
  }
}
