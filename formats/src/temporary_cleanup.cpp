// temporary_cleanup.cpp: removing the temporary body file on SIGINT, SIGTERM and SIGHUP
// (remove_temporary_body_file_on_signal, body_file.hpp; temporary_cleanup.hpp).
//
// The path lives in a static buffer that the handler reads without locks or allocation: the writer clears the
// `armed` flag, writes the path, then sets the flag, so the handler sees either no path or a whole one. The handler
// makes only async-signal-safe calls (unlink, sigaction, raise).
#include "temporary_cleanup.hpp"

#include "flexbody/format/body_file.hpp"

#include <signal.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <climits>
#include <cstring>
#include <system_error>

namespace flexbody::format {
namespace {

std::array<char, PATH_MAX> temporary_path{};
volatile sig_atomic_t armed = 0;
constexpr std::array<int, 3> kSignals = {SIGINT, SIGTERM, SIGHUP};

extern "C" void remove_temporary_and_reraise(int signal_number) {
  if (armed != 0) (void)::unlink(temporary_path.data());
  struct sigaction default_action {};
  default_action.sa_handler = SIG_DFL;
  sigemptyset(&default_action.sa_mask);
  (void)::sigaction(signal_number, &default_action, nullptr);
  (void)::raise(signal_number);  // blocked while this handler runs: delivered, with the default action, on return
}

}  // namespace

void remove_temporary_body_file_on_signal() {
  for (const int signal_number : kSignals) {
    struct sigaction old {};
    if (::sigaction(signal_number, nullptr, &old) != 0 || old.sa_handler == SIG_IGN) continue;  // nohup: stays ignored
    struct sigaction action {};
    action.sa_handler = remove_temporary_and_reraise;
    sigemptyset(&action.sa_mask);
    for (const int other : kSignals) sigaddset(&action.sa_mask, other);  // one cleanup at a time
    (void)::sigaction(signal_number, &action, nullptr);
  }
}

namespace detail {

TemporaryFileGuard::TemporaryFileGuard(const std::filesystem::path& path) {
  std::error_code error;
  std::filesystem::path absolute = std::filesystem::absolute(path, error);
  const std::string text = error ? path.string() : absolute.string();
  armed = 0;
  std::atomic_signal_fence(std::memory_order_seq_cst);
  if (text.size() >= temporary_path.size()) return;  // not recorded: the handler then removes nothing
  std::memcpy(temporary_path.data(), text.c_str(), text.size() + 1);
  std::atomic_signal_fence(std::memory_order_seq_cst);
  armed = 1;
}

TemporaryFileGuard::~TemporaryFileGuard() {
  armed = 0;
  std::atomic_signal_fence(std::memory_order_seq_cst);
}

}  // namespace detail
}  // namespace flexbody::format
