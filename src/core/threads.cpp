#include "vsd/core/threads.hpp"

#include <dlfcn.h>

namespace vsd {

void setBlasThreads(int threads) {
  // Looked up at run time: no link-time dependency on OpenBLAS.
  using SetThreads = void (*)(int);
  if (auto* set = reinterpret_cast<SetThreads>(::dlsym(RTLD_DEFAULT, "openblas_set_num_threads"))) set(threads);
}

}  // namespace vsd
