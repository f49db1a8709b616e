#pragma once
// parallel.hpp (internal): when the runtime's per-body loops run on OpenMP's threads. Each body's work writes only
// that body's storage and is the same arithmetic on any thread, so results are bit-identical for any thread count;
// what several bodies add into shared rows (joints, springs) is summed afterwards, in body or joint order.

namespace flexbody::runtime::detail {

/// From this many bodies (or joints) on, a per-body loop runs in parallel. A GCMS body's forces take ~1 µs at 6 modes,
/// and a parallel region costs a few µs to start on an idle machine but far more when another process holds a core:
/// a 16-body chain's per-iteration loops on two threads ran 30 times slower than on one while a second process ran
/// (libgomp's waiting threads lose their core), so only loops of some 64 µs and more are split.
inline constexpr int kParallelFrom = 64;

}  // namespace flexbody::runtime::detail
