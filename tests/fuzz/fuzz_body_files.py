#!/usr/bin/python3
"""Fuzz run of flexbody body files through both entry points (issue 13).

Two small valid body files are made with fbprep (a box with its default whole-body region; the same box with
two rbe3 interfaces, a load point and two output regions), then copies of them are changed and each copy goes
through `fbprep inspect --json FILE` and through `fbsim SCENE` with a scene that loads it. Three families of
changes, each case reproducible from (family, seed, index) alone:

  sealed     byte-level changes of the sealed file (bit flips, zeroed or overwritten blocks, truncations, spliced
             bytes; half aimed at the first 4 KiB, a quarter at HDF5 metadata): the seal must refuse every one as
             damaged (exit code 2, "damaged or modified after it was written").
  resealed   the same changes after the 512-byte seal, then re-sealed with hashlib exactly as formats/SCHEMA.md
             shows: libhdf5 and the semantic checks see the damage. A file may be refused or accepted (a flipped
             bit in raw data can be a plausible value), but never with a signal, a hang, bad_alloc or more than
             one line.
  checksummed  byte-level changes inside HDF5's checksummed metadata (the version-2 superblock and object
             headers), with HDF5's lookup3 checksum and the seal recomputed: what an attacker who knows the format
             hands libhdf5 (a review crashed it in 3 of 300 such files). May be refused or accepted.
  semantic   edits with h5py, then re-sealed: deleted, reshaped and retyped datasets and attributes, NaN and Inf,
             asymmetric or indefinite G, K_hat with a negative eigenvalue, wrong format versions, strings for
             numbers, variable-length strings, huge declared dimensions, out-of-range indices, filters, external
             storage and links, soft-link loops, long strings with control characters, scaled stress modes...
             Each case is tagged "must refuse" (an acceptance is a silent acceptance) or "may accept", with the
             reason next to the mutator.

Forbidden outcomes (the script exits 1 if any occurs): a signal, a hang (the time limit), bad_alloc (or
length_error), a sanitizer report, a silent acceptance, stderr other than exactly one `TOOL: error:` line on a
refusal (fbsim may add its `fbsim: warning:` lines), a line from the HDF5 library, control characters on stderr,
anything on stderr when inspect accepts, stdout on a refusal, a line over --max-line bytes, and, for the sealed family, any answer but the seal's.

Requires Python 3 with numpy and h5py (Debian: python3-h5py); without h5py it exits with code 77 (ctest SKIP).
Run `fuzz_body_files.py --help` for the options; docs/accuracy-and-speed.md ("Other checks the tests make") gives the long run.
"""

import argparse
import collections
import concurrent.futures
import json
import multiprocessing
import os
import random
import shutil
import sys
import tempfile
import time

try:  # the families need h5py and numpy; without them the run is skipped
    import h5py  # noqa: F401
    import numpy  # noqa: F401
except ImportError as error:  # ctest SKIP_RETURN_CODE
    print(f"fuzz_body_files.py: skipped: {error} (install python3-h5py)")
    sys.exit(77)

# The families and the tools' runs, one module each beside this script.
from fuzz_base import BASES, FAMILIES, MAY, MUST, SCENES, SEAL, make_bases, metadata_ranges, seal_bytes
from fuzz_bytes import byte_mutation, checksummed_mutation, checksummed_structures
from fuzz_semantic_edits import MUTATORS, semantic_mutation
from fuzz_tools import FORBIDDEN, OUTCOMES, classify, run_bounded

# ----------------------------------------------------------------------------------------------------------------
# Cases


def case_id(family, seed, index):
    return f"{family}:{seed}:{index}"


def parse_case_id(text):
    try:
        family, seed, index = text.split(":")
        assert family in FAMILIES
        return family, int(seed), int(index)
    except (ValueError, AssertionError):
        raise SystemExit(f"fuzz_body_files.py: a case id is FAMILY:SEED:INDEX with FAMILY one of {', '.join(FAMILIES)}, "
                         f"got '{text}'")


def case_rng(family, seed, index):
    return random.Random(f"flexbody-fuzz {family} {seed} {index}")  # str seeds hash with SHA-512: stable


STATE = {}


def init_worker(config):
    STATE.update(config)
    STATE["bytes"] = {}
    STATE["meta"] = {}
    STATE["structures"] = {}
    for name, path in config["bases"].items():
        with open(path, "rb") as fh:
            STATE["bytes"][name] = fh.read()
        STATE["meta"][name] = metadata_ranges(path, len(STATE["bytes"][name]))
        STATE["structures"][name] = checksummed_structures(STATE["bytes"][name])
        if len(STATE["structures"][name]) < 2:  # the superblock and at least one object header whose checksum matched
            raise SystemExit(f"fuzz_body_files.py: {path}: no version-2 HDF5 object headers with a matching lookup3 "
                             "checksum; the checksummed family needs them")


def run_case(family, seed, index, keep=False):
    rng = case_rng(family, seed, index)
    base = BASES[index % 2] if family != "semantic" else "bar"
    good = STATE["bytes"][base]
    work = tempfile.mkdtemp(prefix=f"{family}-{index}-", dir=STATE["work"])
    path = os.path.join(work, "case.fbh5")
    result = {"id": case_id(family, seed, index), "family": family, "index": index, "base": base}
    try:
        if family == "semantic":
            kind, description, tag, reason = semantic_mutation(good, rng, seed, index, work, path)
        elif family == "checksummed":
            data, description = checksummed_mutation(good, STATE["structures"][base], rng)
            with open(path, "wb") as fh:
                fh.write(data)
            kind = description.split(" at ")[0]
            tag, reason = MAY, "changed HDF5 metadata with valid checksums and seal: may read as another valid file"
        else:
            floor = 0 if family == "sealed" else SEAL
            data, description = byte_mutation(good, STATE["meta"][base], rng, index, floor)
            if family == "resealed":
                data = seal_bytes(data)
            with open(path, "wb") as fh:
                fh.write(data)
            kind = description.split(" (")[0]
            tag, reason = (MUST, "the seal must refuse it as damaged") if family == "sealed" else \
                (MAY, "damaged bytes under a valid seal: a changed value can be plausible")
    except Exception as error:  # a mutator that could not be applied is a harness bug: report it loudly
        shutil.rmtree(work, ignore_errors=True)
        result.update(kind="harness error", description=f"{type(error).__name__}: {error}", tag=MAY, reason="",
                      tools={}, harness_error=True)
        return result
    result.update(kind=kind, description=description, tag=tag, reason=reason, tools={})
    with open(os.path.join(work, "scene.yaml"), "w") as fh:
        fh.write(SCENES[base])
    commands = {"fbprep": [STATE["fbprep"], "inspect", "--json", "case.fbh5"],
                "fbsim": [STATE["fbsim"], "scene.yaml", "-o", "out", "-q"]}
    failed = False
    for tool, command in commands.items():
        run = run_bounded(command, work, STATE["timeout"], STATE["mem_limit"], STATE["env"])
        outcome, note = classify(tool, run, family, tag, STATE["max_line"])
        failed |= outcome in FORBIDDEN
        result["tools"][tool] = {"outcome": outcome, "note": note, "exit_code": run.exit_code, "signal": run.signal,
                                 "timed_out": run.timed_out, "seconds": round(run.elapsed, 3),
                                 "stderr": run.err[:2000], "stderr_lines": len(run.err.splitlines())}
        with open(os.path.join(work, f"{tool}.stderr"), "w") as fh:
            fh.write(run.err)
        with open(os.path.join(work, f"{tool}.stdout"), "w") as fh:
            fh.write(run.out[:65536])
    result["failed"] = failed
    shutil.rmtree(os.path.join(work, "out"), ignore_errors=True)
    if failed or keep:
        keep_dir = os.path.join(STATE["out"], "failures" if failed and not keep else "cases",
                                result["id"].replace(":", "-"))
        shutil.rmtree(keep_dir, ignore_errors=True)
        shutil.move(work, keep_dir)
        with open(os.path.join(keep_dir, "case.json"), "w") as fh:
            json.dump(result, fh, indent=1)
        result["kept"] = keep_dir
    else:
        shutil.rmtree(work, ignore_errors=True)
    return result


# ----------------------------------------------------------------------------------------------------------------
# Report


def table(results):
    counts = collections.OrderedDict()
    for fam in FAMILIES:
        for tool in ("fbprep", "fbsim"):
            counts[(fam, tool)] = collections.Counter()
    for r in results:
        for tool, t in r["tools"].items():
            counts[(r["family"], tool)][t["outcome"]] += 1
    used = [o for o in OUTCOMES if any(c[o] for c in counts.values())]
    head = "| family | tool | cases | " + " | ".join(used) + " |"
    lines = [head, "|" + "---|" * (3 + len(used))]
    for (fam, tool), c in counts.items():
        n = sum(c.values())
        if n:
            lines.append(f"| {fam} | {tool} | {n} | " + " | ".join(str(c[o]) for o in used) + " |")
    return "\n".join(lines)


def kind_table(results):
    """Per semantic mutator: cases, tag counts and outcomes of both tools, so gaps in may-accept kinds show."""
    rows = collections.OrderedDict()
    for r in results:
        if r["family"] != "semantic":
            continue
        row = rows.setdefault(r["kind"], collections.Counter())
        row["cases"] += 1
        for tool, t in r["tools"].items():
            row[f"{tool} {t['outcome']}"] += 1
    lines = ["| semantic kind | cases | fbprep | fbsim |", "|---|---|---|---|"]
    for kind, c in rows.items():
        def cell(tool):
            return ", ".join(f"{o} {c[f'{tool} {o}']}" for o in OUTCOMES if c[f"{tool} {o}"])
        lines.append(f"| {kind} | {c['cases']} | {cell('fbprep')} | {cell('fbsim')} |")
    return "\n".join(lines)


def failure_list(results, limit):
    lines = []
    for r in results:
        if not r.get("failed") and not r.get("harness_error"):
            continue
        if r.get("harness_error"):
            lines.append(f"- {r['id']}: HARNESS ERROR {r['description']}")
            continue
        bad = ", ".join(f"{tool}: {t['outcome']} ({' '.join(t['note'].split())[:160]})" if t["note"] else
                        f"{tool}: {t['outcome']}"
                        for tool, t in r["tools"].items() if t["outcome"] in FORBIDDEN)
        lines.append(f"- {r['id']} [{r['kind']}; {r['tag']}] {r['description'][:160]}: {bad}")
    if len(lines) > limit:
        lines = lines[:limit] + [f"- ... and {len(lines) - limit} more (results.jsonl)"]
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cases", type=int, default=100, help="cases per family (default 100)")
    parser.add_argument("--families", default=",".join(FAMILIES), help="comma-separated subset of " + ", ".join(FAMILIES))
    parser.add_argument("--seed", type=int, default=20261123, help="the run's seed (default 20261123)")
    parser.add_argument("--jobs", type=int, default=2, help="cases run in parallel (default 2)")
    parser.add_argument("--fbprep", default=shutil.which("fbprep") or "fbprep")
    parser.add_argument("--fbsim", default=shutil.which("fbsim") or "fbsim")
    parser.add_argument("--out", default=None, help="output directory: base files, results.jsonl, summary.md, "
                        "failures/<id>/ (default: a new directory under /tmp)")
    parser.add_argument("--timeout", type=float, default=10.0, help="seconds per tool run (default 10)")
    parser.add_argument("--mem-limit", type=int, default=4096, help="address-space limit per tool run in MiB, so "
                        "that a huge allocation fails as bad_alloc instead of swapping (default 4096; 0 = none, "
                        "needed with AddressSanitizer)")
    parser.add_argument("--max-line", type=int, default=2000, help="longest stderr line in bytes (default 2000)")
    parser.add_argument("--case", action="append", default=[], metavar="FAMILY:SEED:INDEX",
                        help="run only this case (repeatable), keep its files in OUT/cases/ and print it")
    parser.add_argument("--list-kinds", action="store_true", help="print the semantic mutators and exit")
    args = parser.parse_args()

    if args.list_kinds:
        for i, (name, _) in enumerate(MUTATORS):
            print(f"{i:3} {name}")
        return 0
    families = [x for x in args.families.split(",") if x]
    if any(x not in FAMILIES for x in families):
        parser.error(f"--families: one of {', '.join(FAMILIES)}")
    for tool in ("fbprep", "fbsim"):
        path = getattr(args, tool)
        if not (os.path.isfile(path) and os.access(path, os.X_OK)):
            parser.error(f"--{tool}: no executable '{path}'")
    out = os.path.abspath(args.out or tempfile.mkdtemp(prefix="fuzz-body-files-"))
    os.makedirs(out, exist_ok=True)
    shutil.rmtree(os.path.join(out, "failures"), ignore_errors=True)
    work = os.path.join(out, "work")
    os.makedirs(work, exist_ok=True)

    started = time.monotonic()
    bases = make_bases(os.path.abspath(args.fbprep), os.path.join(out, "base"), args.timeout)
    env = dict(os.environ, LC_ALL="C")
    config = {"bases": bases, "fbprep": os.path.abspath(args.fbprep), "fbsim": os.path.abspath(args.fbsim),
              "timeout": args.timeout, "mem_limit": args.mem_limit, "max_line": args.max_line, "out": out,
              "work": work, "env": env}

    # The base files themselves must read through both tools, or every answer below means nothing.
    init_worker(config)
    for base in BASES:
        check = tempfile.mkdtemp(dir=work)
        shutil.copy(bases[base], os.path.join(check, "case.fbh5"))
        with open(os.path.join(check, "scene.yaml"), "w") as fh:
            fh.write(SCENES[base])
        for tool, command in {"fbprep": [config["fbprep"], "inspect", "--json", "case.fbh5"],
                              "fbsim": [config["fbsim"], "scene.yaml", "-o", "out", "-q"]}.items():
            run = run_bounded(command, check, max(args.timeout, 60), args.mem_limit, env)
            if run.exit_code != 0 or run.err:
                raise SystemExit(f"fuzz_body_files.py: the unchanged {base}.fbh5 does not pass {tool} "
                                 f"(exit {run.exit_code}, signal {run.signal}): {run.err.strip()[:500]}")
        shutil.rmtree(check)

    if args.case:
        keep = True
        todo = [parse_case_id(c) for c in args.case]
    else:
        keep = False
        todo = [(fam, args.seed, i) for fam in families for i in range(args.cases)]

    results = []
    if args.jobs <= 1 or len(todo) == 1:
        results = [run_case(*t, keep=keep) for t in todo]
    else:
        context = multiprocessing.get_context("fork")
        with concurrent.futures.ProcessPoolExecutor(args.jobs, mp_context=context, initializer=init_worker,
                                                    initargs=(config,)) as pool:
            futures = [pool.submit(run_case, *t, keep=keep) for t in todo]
            step, done, failing = max(100, len(todo) // 20), 0, 0
            for fut in concurrent.futures.as_completed(futures):
                done += 1
                failing += bool(fut.result().get("failed"))
                if done % step == 0 and done < len(todo):
                    print(f"fuzz_body_files.py: {done} of {len(todo)} cases, {failing} with a forbidden outcome, "
                          f"{time.monotonic() - started:.0f} s", file=sys.stderr, flush=True)
            results = [fut.result() for fut in futures]
    elapsed = time.monotonic() - started
    shutil.rmtree(work, ignore_errors=True)

    with open(os.path.join(out, "results.jsonl"), "w") as fh:
        for r in results:
            fh.write(json.dumps(r) + "\n")
    failed = [r for r in results if r.get("failed")]
    harness = [r for r in results if r.get("harness_error")]
    summary = [f"# Body-file fuzz run: seed {args.seed}, {len(results)} cases ({len(results) * 2} tool runs), "
               f"{elapsed:.1f} s with {args.jobs} jobs", "", table(results), ""]
    if any(r["family"] == "semantic" for r in results):
        summary += [kind_table(results), ""]
    summary += [f"{len(failed)} cases with a forbidden outcome" + (f", {len(harness)} harness errors" if harness else "")
                + (f" (kept in {out}/failures)" if failed else ""), ""]
    if failed or harness:
        summary += [failure_list(results, 200), ""]
    text = "\n".join(summary)
    with open(os.path.join(out, "summary.md"), "w") as fh:
        fh.write(text)
    print(text)
    if args.case:
        for r in results:
            print(json.dumps(r, indent=1))
    print(f"output: {out}")
    return 1 if failed or harness else 0


if __name__ == "__main__":
    sys.exit(main())
