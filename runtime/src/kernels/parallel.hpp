#pragma once
// parallel.hpp (internal): when the runtime's per-body loops run on OpenMP's threads. Each body's work writes only
// that body's storage and is the same arithmetic on any thread, so results are bit-identical for any thread count;
// what several bodies add into shared rows (joints, springs) is summed afterwards, in body or joint order.

#include "flexbody/runtime/threads.hpp"

#include <exception>

namespace flexbody::runtime::detail {

/// From this many bodies (or joints) on, a per-body loop runs in parallel. A GCMS body's forces take ~1 µs at 6 modes,
/// and a parallel region costs a few µs to start on an idle machine but far more when another process holds a core:
/// a 16-body chain's per-iteration loops on two threads ran 30 times slower than on one while a second process ran
/// (libgomp's waiting threads lose their core), so only loops of some 64 µs and more are split.
inline constexpr int kParallelFrom = 64;

/// f(k) for k = 0 ... count − 1: on OpenMP's threads from kParallelFrom on, in a plain loop below it. (Not an
/// `if` clause: a parallel region that runs on one thread still costs about 1 µs to enter, which made a one-body
/// step of a rigid pendulum 2.8 times slower.) On one thread unless set_threads asked for more (threads.hpp).
template <class F>
void for_each(int count, F&& f) {
  if (const int threads = runtime::threads(); threads > 1 && count >= kParallelFrom) {
    // An exception must not leave an OpenMP region (it would end the program): the first one is kept and rethrown.
    std::exception_ptr failure;
#pragma omp parallel for schedule(static) num_threads(threads)
    for (int k = 0; k < count; ++k) {
      try {
        f(k);
      } catch (...) {
#pragma omp critical(flexbody_for_each_failure)
        if (!failure) failure = std::current_exception();
      }
    }
    if (failure) std::rethrow_exception(failure);
  } else {
    for (int k = 0; k < count; ++k) f(k);
  }
}

}  // namespace flexbody::runtime::detail
