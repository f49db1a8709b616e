#include "bounded_run.hpp"

#include "cli_run.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <thread>

namespace flexbody::test {

BoundedRun run_bounded(const std::string& executable, const std::vector<std::string>& arguments,
                       const std::filesystem::path& output_stem, std::chrono::duration<double> limit,
                       const std::function<bool()>& interrupt_when, int signal) {
  const std::string out_path = output_stem.string() + ".out";
  const std::string err_path = output_stem.string() + ".err";
  std::vector<char*> argv;
  argv.push_back(const_cast<char*>(executable.c_str()));
  for (const std::string& argument : arguments) argv.push_back(const_cast<char*>(argument.c_str()));
  argv.push_back(nullptr);

  BoundedRun run;
  const auto start = std::chrono::steady_clock::now();
  const pid_t child = ::fork();
  if (child == 0) {  // only async-signal-safe calls until exec
    const int out = ::open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int err = ::open(err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (out < 0 || err < 0 || ::dup2(out, STDOUT_FILENO) < 0 || ::dup2(err, STDERR_FILENO) < 0) ::_exit(127);
    ::execv(executable.c_str(), argv.data());
    ::_exit(127);
  }
  if (child < 0) return run;
  int status = 0;
  bool interrupted = false;
  for (;;) {
    const pid_t done = ::waitpid(child, &status, WNOHANG);
    if (done == child) break;
    if (interrupt_when && !interrupted && interrupt_when()) {
      ::kill(child, signal);
      interrupted = true;
    }
    if (std::chrono::steady_clock::now() - start > limit) {
      run.timed_out = true;
      ::kill(child, SIGKILL);
      ::waitpid(child, &status, 0);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  run.elapsed = std::chrono::steady_clock::now() - start;
  if (!run.timed_out && WIFEXITED(status)) run.exit_code = WEXITSTATUS(status);
  if (!run.timed_out && WIFSIGNALED(status)) run.signal = WTERMSIG(status);
  run.out = slurp(out_path);
  run.err = slurp(err_path);
  return run;
}

}  // namespace flexbody::test
