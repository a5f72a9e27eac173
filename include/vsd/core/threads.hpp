#pragma once
// Thread pools of the numeric libraries.

namespace vsd {

/// Sets OpenBLAS's own thread pool (Debian's libopenblas0-pthread behind libblas.so.3)
/// to `threads`, if OpenBLAS is the BLAS in use; a no-op for other BLAS libraries.
/// libtorch callers keep it at 1 and parallelise with libtorch's pool instead: two
/// pools on two cores spin against each other and halve the speed.
void setBlasThreads(int threads);

}  // namespace vsd
