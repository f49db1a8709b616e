# How the project's libraries and tools are compiled: in unity batches (several sources per compiler run).
#
# Most of a source's compile time is Eigen: parsing it (about 2 s a source) and instantiating and optimizing the same
# products and decompositions in every source that uses them. A batch of four sources does both once per batch. On 2
# cores fbprep and fbsim (117 sources, 35 batches) built from scratch in 3 min 44 s and 3 min 37 s instead of 5 min 43 s
# and 5 min 27 s (two pairs of runs, each pair back to back; compiler CPU time 6.5 and 6.3 min instead of 10.1 and
# 9.6). Batches of 8 took 4 min 8 s in one run (fewer, larger units leave a core idle at the end); precompiling
# Eigen's headers on top of the batches took 5 min 10 s (not kept).
# Sources in a batch share a translation unit, so names at namespace scope (also in anonymous namespaces) must be
# unique within a library: a build with the batches fails on two definitions of a name, but not on two file-local
# overloads of one name, which would serve each other's calls (so helpers get distinct names). Turn it off
# while editing one file often: a batch recompiles as a whole.
#
# A batch inlines differently from a source compiled alone, so it can expose what a single source hides: a heap
# allocation in Eigen's SimplicialLLT::solve (an in-place permutation's mask) showed up only in batches, because
# compiled alone GCC fused its malloc and memset into a calloc that tests/runtime/allocation_test.cpp did not count.
# The projection now permutes out of place and the test counts calloc; run the tests with the batches on and off
# after touching the Newton iteration.
option(FLEXBODY_UNITY_BUILD "Compile the libraries, fbprep and fbsim in batches of 4 sources (faster from scratch)"
       ON)

function(flexbody_compile_in_batches)
  if(FLEXBODY_UNITY_BUILD)
    set_target_properties(${ARGN} PROPERTIES UNITY_BUILD ON UNITY_BUILD_MODE BATCH UNITY_BUILD_BATCH_SIZE 4)
  endif()
endfunction()
