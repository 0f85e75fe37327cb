// Calls tune_libtorch_runtime() as the LibTorch programs do, then prints the
// two variables it sets and the name the process goes by (ps, top, pkill:
// the re-executed program was once called "exe"), for the tests in
// CMakeLists.txt to match.
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>

#include "ivoa/introspection/model.hpp"

int main(int, char** argv) {
  ivoa::introspection::tune_libtorch_runtime(argv);
  for (const char* name : {"OMP_WAIT_POLICY", "GLIBC_TUNABLES"}) {
    const char* value = std::getenv(name);
    std::cout << name << '=' << (value ? value : "(unset)") << '\n';
  }
  std::string comm;
  std::getline(std::ifstream("/proc/self/comm"), comm);
  std::cout << "process name=" << comm << '\n';
}
