#include "flexbody/runtime/threads.hpp"

#include <atomic>
#include <stdexcept>
#include <string>

namespace flexbody::runtime {
namespace {
std::atomic<int> chosen{1};
}

void set_threads(int threads) {
  if (threads < 1) throw std::invalid_argument("threads must be at least 1, got " + std::to_string(threads));
  chosen.store(threads);
}

int threads() { return chosen.load(std::memory_order_relaxed); }

}  // namespace flexbody::runtime
