#!/usr/bin/python3
"""fbprep at its defaults on public CAD parts that nobody here wrote, with linear and quadratic tetrahedra (issue 28).

The corpus: every STEP and IGES model of FreeCAD's Idf component library (Debian package freecad-common,
/usr/share/freecad/Mod/Idf/Idflibs) and gmsh's demo part component8.step (gmsh-doc, gunzipped into the work
folder), and the 18 solids of gmsh's demo assembly as1-tu-203, each written on its own as BREP by the gmsh command
(read with --unit mm). scripts/setup.sh installs freecad-common and gmsh-doc.

Each part runs `fbprep PART --order O --json` for O = 1 and 2 (default modes, mesh size and material). Per run:
the outcome (a body file, or fbprep's one-line refusal), wall time, DOFs, mass, the first elastic frequency, the
mesh's volume against the CAD solid's, the first frequency's estimated discretisation error, and what was done about
folded quadratic elements. Writes bench/results/cad_corpus_bench.csv and prints
a table with the first frequency's change from linear to quadratic elements.

    /usr/bin/python3 bench/cad_corpus_bench.py [--build build] [--work bench/results/work/corpus] [--only NAME ...]
                                               [--args "FBPREP OPTIONS" --tag NAME]

--args adds options to every run (e.g. "--thin-features 1"); --tag names the CSV (cad_corpus_bench_NAME.csv), so a
variant does not overwrite the defaults' results.
"""
import argparse
import csv
import gzip
import json
import shutil
import subprocess
import sys
import time
from pathlib import Path

FREECAD = Path("/usr/share/freecad/Mod/Idf/Idflibs")
GMSH_DEMOS = Path("/usr/share/doc/gmsh-doc/doc/gmsh/demos/boolean")


# Writes solid K of a STEP assembly on its own as BREP (the gmsh command; BREP carries no unit: read as mm).
SPLIT_GEO = """SetFactory("OpenCASCADE");
v() = ShapeFromFile(Source);
For i In {0:#v()-1}
  If (i != K)
    Recursive Delete { Volume{v(i)}; }
  EndIf
EndFor
Save StrCat(Target, "");
"""


def gunzipped(gz, work):
    target = work / gz.name[:-3]
    if not target.exists():
        with gzip.open(gz, "rb") as src, open(target, "wb") as dst:
            shutil.copyfileobj(src, dst)
    return target


def corpus(work):
    """(path, extra fbprep arguments) of every part."""
    parts = [(p, []) for p in sorted(FREECAD.glob("*")) if p.suffix.lower() in (".stp", ".step", ".igs", ".iges")]
    if (GMSH_DEMOS / "component8.step.gz").exists():
        parts.append((gunzipped(GMSH_DEMOS / "component8.step.gz", work), []))
    if (GMSH_DEMOS / "as1-tu-203.stp.gz").exists():  # the assembly's 18 solids, each as its own file
        assembly = gunzipped(GMSH_DEMOS / "as1-tu-203.stp.gz", work)
        script = work / "split_solid.geo"
        script.write_text(SPLIT_GEO)
        for k in range(18):
            target = work / f"as1-tu-203_solid{k:02d}.brep"
            if not target.exists():
                subprocess.run(["gmsh", "-setstring", "Source", str(assembly), "-setstring", "Target", str(target),
                                "-setnumber", "K", str(k), "-0", str(script), "-o", str(work / "split.geo_unrolled")],
                               check=True, capture_output=True)
            parts.append((target, ["--unit", "mm"]))
    return parts


def run(fbprep, part, extra, order, work, tag=""):
    out = work / f"{part.stem}_{part.suffix[1:].lower()}_o{order}{'_' + tag if tag else ''}.fbh5"
    start = time.monotonic()
    proc = subprocess.run([str(fbprep), str(part), "--order", str(order), "--json", "-o", str(out)] + extra,
                          capture_output=True, text=True)
    seconds = time.monotonic() - start
    row = {"part": part.name, "order": order, "seconds": round(seconds, 2)}
    if proc.returncode != 0:
        lines = [l for l in proc.stderr.splitlines() if l.strip()]
        row["outcome"] = "refused"
        row["message"] = lines[-1] if lines else f"exit {proc.returncode}"
        return row
    d = json.loads(proc.stdout)
    folded = d.get("folded_elements") or {}
    row.update(outcome="body file", mesh_size_m=d["mesh_size_m"], dofs=d["dofs"], mass_kg=d["mass_kg"],
               volume_m3=d["mesh_quality"]["volume_m3"], cad_volume_m3=d["cad_volume_m3"],
               volume_error=d["volume_error"], refined_from_m=d.get("mesh_size_refined_from_m"),
               sewn_faces=d.get("sewn_faces"), loose_faces=d.get("loose_faces"),
               first_hz=d["frequencies_hz"][0] if d["frequencies_hz"] else "",
               first_error_estimate=(d.get("frequency_error_estimates") or [""])[0],
               folded=folded.get("after_order_2", ""), folded_after_gmsh=folded.get("after_gmsh_elastic", ""),
               straightened=folded.get("straightened_elements", ""),
               largest_move_m=folded.get("largest_move_m", ""))
    return row


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    here = Path(__file__).resolve().parent
    ap.add_argument("--build", default=str(here.parent / "build"))
    ap.add_argument("--work", default=str(here / "results" / "work" / "corpus"))
    ap.add_argument("--only", nargs="*", help="part file names to run (default: all)")
    ap.add_argument("--args", default="", help="fbprep options added to every run")
    ap.add_argument("--tag", default="", help="results go to cad_corpus_bench_TAG.csv (needed with --args)")
    args = ap.parse_args()
    if args.args and not args.tag:
        sys.exit("cad_corpus_bench: --args needs --tag, so that the defaults' results are not overwritten")
    fbprep = Path(args.build) / "bin" / "fbprep"
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    if not FREECAD.is_dir():
        sys.exit(f"cad_corpus_bench: {FREECAD} is missing: apt-get install freecad-common gmsh-doc")
    parts = [(p, extra) for p, extra in corpus(work) if not args.only or p.name in args.only]
    rows = []
    for part, extra in parts:
        for order in (1, 2):
            row = run(fbprep, part, extra + args.args.split(), order, work, args.tag)
            rows.append(row)
            print(f"{row['part']:<34} order {order}: {row['outcome']:<9} {row['seconds']:6.1f} s  "
                  + (row.get("message", "") if row["outcome"] == "refused"
                     else f"{row['dofs']:>7} DOFs  f1 {row['first_hz']:.5g} Hz  volume "
                          f"{100 * (row['volume_error'] or 0):+.2f} %  folded {row['folded']}"
                          f"/{row['folded_after_gmsh']}/{row['straightened']}"), flush=True)
    fields = ["part", "order", "outcome", "seconds", "mesh_size_m", "dofs", "mass_kg", "volume_m3", "cad_volume_m3", "volume_error", "refined_from_m", "sewn_faces", "loose_faces",
              "first_hz", "first_error_estimate", "folded",
              "folded_after_gmsh", "straightened", "largest_move_m", "message"]
    results = here / "results" / f"cad_corpus_bench{'_' + args.tag if args.tag else ''}.csv"
    with open(results, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields)
        w.writeheader()
        w.writerows(rows)
    by_part = {}
    for r in rows:
        by_part.setdefault(r["part"], {})[r["order"]] = r
    both = [(p, o) for p, o in by_part.items() if o[1]["outcome"] == "body file"]
    linear_only = [p for p, o in by_part.items() if o[1]["outcome"] == "body file" and o[2]["outcome"] != "body file"]
    print(f"\n{len(both)} parts give body files with linear elements; {len(linear_only)} of them not with quadratic "
          f"ones{': ' + ', '.join(linear_only) if linear_only else ''}")
    def pct(x):
        return f"{100 * x:7.1f}%" if isinstance(x, float) else f"{'-':>8}"

    print(f"\n{'part':<34} {'f1 linear':>11} {'f1 quadratic':>13} {'change':>8} {'est. lin':>8} {'est. quad':>9} "
          f"{'s lin':>6} {'s quad':>6}")
    for p, o in both:
        if o[2]["outcome"] == "body file" and o[1]["first_hz"] and o[2]["first_hz"]:
            print(f"{p:<34} {o[1]['first_hz']:11.5g} {o[2]['first_hz']:13.5g} "
                  f"{pct(o[1]['first_hz'] / o[2]['first_hz'] - 1)} {pct(o[1].get('first_error_estimate'))} "
                  f"{pct(o[2].get('first_error_estimate')):>9} {o[1]['seconds']:6.1f} {o[2]['seconds']:6.1f}")
    print(f"\nwrote {results}")


if __name__ == "__main__":
    main()
