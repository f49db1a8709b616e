"""fuzz_body_files.py's runs of fbprep inspect and fbsim under limits, and the outcomes they are sorted into."""
import os
import re
import resource
import signal
import subprocess
import time


from fuzz_base import DAMAGED, MUST


# ----------------------------------------------------------------------------------------------------------------
# Running the tools


class Run:
    __slots__ = ("exit_code", "signal", "timed_out", "elapsed", "out", "err")


def run_bounded(command, cwd, timeout, mem_limit_mb, env):
    def limits():
        if mem_limit_mb:
            size = mem_limit_mb * 1024 * 1024
            resource.setrlimit(resource.RLIMIT_AS, (size, size))
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))

    r = Run()
    start = time.monotonic()
    proc = subprocess.Popen(command, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL,
                            start_new_session=True, preexec_fn=limits, env=env)
    try:
        out, err = proc.communicate(timeout=timeout)
        r.timed_out = False
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        r.timed_out = True
    r.elapsed = time.monotonic() - start
    r.exit_code = proc.returncode if proc.returncode >= 0 else None
    r.signal = -proc.returncode if proc.returncode < 0 and not r.timed_out else 0
    r.out, r.err = out.decode("utf-8", "replace"), err.decode("utf-8", "replace")
    return r


# Outcomes, in the order of the table. The first group is allowed, the rest forbidden.
ALLOWED = ("refused", "refused as damaged", "accepted", "run stopped")
FORBIDDEN = ("silent acceptance", "signal", "timeout", "bad_alloc", "sanitizer", "not one line", "library noise",
             "control characters", "overlong line", "stdout on refusal", "stderr on acceptance", "not refused as damaged")
OUTCOMES = ALLOWED + FORBIDDEN


def classify(tool, run, family, tag, max_line):
    """Returns the run's outcome (one of OUTCOMES) and a short note."""
    prefix = f"{tool}: "
    # ASAN_OPTIONS=allocator_may_return_null=1 makes ASan's malloc fail as the C library's does (libhdf5 then
    # reports an error) and say so on a line of its own, which is not the tool's
    lines = [l for l in run.err.splitlines() if not re.match(r"==\d+==WARNING: AddressSanitizer failed to allocate", l)]
    errors = [l for l in lines if not l.startswith("fbsim: warning: ")] if tool == "fbsim" else lines
    if run.timed_out:
        return "timeout", f"still running after {run.elapsed:.1f} s"
    if run.signal:
        name = signal.Signals(run.signal).name if run.signal in signal.Signals._value2member_map_ else str(run.signal)
        return "signal", f"killed by {name}" + (f"; stderr: {run.err.strip()[:300]}" if run.err.strip() else "")
    err = "\n".join(lines)
    if re.search(r"bad_alloc|length_error|bad_array_new_length|cannot allocate|out of memory", err, re.I):
        return "bad_alloc", err.strip()[:300]
    if re.search(r"Sanitizer|runtime error:", err):
        return "sanitizer", err.strip()[:300]
    if any(len(l.encode()) > max_line for l in lines):
        return "overlong line", f"a stderr line of {max(len(l.encode()) for l in lines)} bytes"
    if any(not l.startswith(prefix) for l in lines):  # e.g. HDF5-DIAG or "HDF5: infinite loop closing library"
        return "library noise", run.err.strip()[:300]
    if re.search(r"[\x00-\x09\x0b-\x1f\x7f]", err):  # text from the file must reach the terminal cleaned
        return "control characters", repr(re.findall(r"[\x00-\x09\x0b-\x1f\x7f]", err)[:5])
    if run.exit_code == 0:
        if errors:
            return "stderr on acceptance", run.err.strip()[:300]
        if family == "sealed":
            return "not refused as damaged", "accepted"
        return ("silent acceptance" if tag == MUST else "accepted"), ""
    if len(errors) != 1 or not errors[0].startswith(prefix + "error: "):
        return "not one line", f"{len(errors)} lines: {run.err.strip()[:300]}"
    if run.out.strip() and (tool == "fbprep" or run.exit_code == 2):
        return "stdout on refusal", run.out.strip()[:200]
    if family == "sealed":
        if run.exit_code == 2 and DAMAGED in errors[0]:
            return "refused as damaged", ""
        return "not refused as damaged", f"exit code {run.exit_code}: {errors[0][:300]}"
    if tool == "fbsim" and run.exit_code == 1:  # the body was read and the run began: the reader accepted it
        return ("silent acceptance" if tag == MUST else "run stopped"), errors[0][:300]
    return "refused", ""
