#pragma once
// flexbody/runtime/threads.hpp: how many threads the runtime's per-body loops use (scenes of 64 bodies and more;
// runtime/src/kernels/parallel.hpp). Results are bit-identical for any count.
//
// The default is one. The loops run every Newton iteration and last tens of µs, so two threads gain 1.4x on a
// 64-body GCMS chain on an idle machine (5.9 -> 4.1 ms per step), but when the cores are shared their waiting
// threads lose them: two such runs side by side on two cores took 154 ms per step each with two threads, 6 ms
// with one. Ask for threads where a run has the cores to itself (fbsim --threads). With more than one, the scene's
// callbacks that joints evaluate (a driven joint's angle φ(t)) may run on several threads at once: they must be
// safe to call so (a pure function of t is).

namespace flexbody::runtime {

/// Sets the threads of the runtime's per-body loops (at least 1; process-wide). Throws std::invalid_argument below 1.
void set_threads(int threads);
[[nodiscard]] int threads();

}  // namespace flexbody::runtime
