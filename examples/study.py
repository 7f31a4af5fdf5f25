#!/usr/bin/env python3
"""A comparison study in one command: methods x meshes x process counts, as the seed paper's
tables and figures.

    python3 examples/study.py MESH [MESH ...] [--methods global local smart_laplace]
        [--ranks 1 2] [--iterations 40] [--partitions 2 4 8 16 32 64] [--out study]

For each mesh it runs:
  - `paloverde partition MESH -n PARTITIONS --json`: the communication of each split (Table 2);
  - every distributed method (global, local) on every process count, with
    `mpiexec -n P paloverde_parallel_benchmark MESH --method M --iterations N`: initialization
    by stage (Table 1), solve time and strong-scaling efficiency T1/(p Tp) (Figs. 3, 5, 6), the
    per-iteration history (Figs. 2, 4) and the peak memory of the ranks;
  - every serial method (smart_laplace, laplace) once, with `paloverde improve`.
It writes to OUT: results.json (everything), results.csv (one row per run), partitions.csv,
report.md (the tables) and the plots quality.png, scaling.png, initialization.png and
partitions.png (python3-matplotlib). Launcher flags come from the build's MPIEXEC_PREFLAGS.
Runs of more than the machine's cores count communication and check results; their times mean
nothing.
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile

DISTRIBUTED = ("global", "local")
SERIAL = ("smart_laplace", "laplace")

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("meshes", nargs="+")
parser.add_argument("--methods", nargs="+", default=["global", "local", "smart_laplace"],
                    choices=DISTRIBUTED + SERIAL)
parser.add_argument("--ranks", nargs="+", type=int, default=[1, 2])
parser.add_argument("--iterations", type=int, default=40, help="iterations (sweeps for local and Laplace)")
parser.add_argument("--partitions", nargs="*", type=int, default=[2, 4, 8, 16, 32, 64])
parser.add_argument("--build", default=os.environ.get("PALOVERDE_BUILD_DIR", "build"))
parser.add_argument("--out", default="study")
args = parser.parse_args()

if any(p < 1 for p in args.ranks) or any(p < 2 for p in args.partitions) or args.iterations < 0:
    sys.exit("study.py: --ranks must be >= 1, --partitions >= 2 and --iterations >= 0")
for mesh in args.meshes:
    if not os.path.isfile(mesh):
        sys.exit(f"study.py: no mesh file {mesh}")
paloverde = os.path.join(args.build, "bin", "paloverde")
benchmark = os.path.join(args.build, "bin", "paloverde_parallel_benchmark")
for program in (paloverde, benchmark):
    if not os.access(program, os.X_OK):
        sys.exit(f"study.py: {program} is missing: build first (bash scripts/setup.sh build)")


def mpiexec_preflags():
    with open(os.path.join(args.build, "CMakeCache.txt")) as cache:
        for line in cache:
            if line.startswith("MPIEXEC_PREFLAGS:"):
                return [f for f in line.split("=", 1)[1].strip().split(";") if f]
    return []


def run(command, may_refuse=False):
    """The command's standard output; with may_refuse, None when the method refuses the mesh."""
    print("$", " ".join(command), file=sys.stderr)
    done = subprocess.run(command, stdout=subprocess.PIPE, text=True, env=dict(os.environ, OMP_NUM_THREADS="1"))
    if done.returncode == 1 and may_refuse:
        return None
    if done.returncode not in (0, 3):  # 3: finished, target not reached, mesh valid
        sys.exit(f"study.py: {command[0]} exited {done.returncode}")
    return done.stdout


preflags = mpiexec_preflags()
results = {"iterations": args.iterations, "meshes": {}}
os.makedirs(args.out, exist_ok=True)
with tempfile.TemporaryDirectory() as scratch:
    for mesh in args.meshes:
        entry = {"runs": []}
        if args.partitions:
            counts = [str(p) for p in args.partitions]
            entry["partitions"] = json.loads(run([paloverde, "partition", mesh, "-n", *counts, "--json"]))["partitions"]
        for method in args.methods:
            if method in DISTRIBUTED:
                for p in args.ranks:
                    out = run(["mpiexec", "-n", str(p), *preflags, benchmark, mesh, "--method", method,
                               "--iterations", str(args.iterations)])
                    entry["runs"].append({"method": method, "ranks": p, "report": json.loads(out)})
            else:
                summary, history = os.path.join(scratch, "summary.json"), os.path.join(scratch, "history.csv")
                # Laplace smoothing refuses a tangled mesh (it cannot untangle): no row then.
                if run([paloverde, "improve", mesh, "-o", os.path.join(scratch, "out.vtu"), "--method", method,
                        "--iterations", str(args.iterations), "--summary", summary, "--history", history,
                        "--threads", "1", "-q"], may_refuse=True) is None:
                    print(f"study.py: {method} refused {mesh}; left out", file=sys.stderr)
                    continue
                report = json.load(open(summary))
                report["history"] = [{k: float(v) for k, v in h.items() if k in ("iteration", "worst_quality", "mean_quality")}
                                     for h in csv.DictReader(open(history))]
                entry["runs"].append({"method": method, "ranks": 1, "report": report})
        results["meshes"][mesh] = entry


def elements(report):
    return report["before"].get("elements")


def mean(report, when):
    """The mean quality before or after, from either kind of summary."""
    if f"mean_{when}" in report:
        return report[f"mean_{when}"]
    return report[when]["metrics"][report["quality_metric"]]["mean"]


rows = []
for mesh, entry in results["meshes"].items():
    base = {}
    for r in entry["runs"]:
        rep, par = r["report"], r["report"].get("parallel")
        sec = par["seconds"] if par else {"solve": rep["seconds"]}
        iterations = max(1, rep["iterations"])
        if r["ranks"] == min(args.ranks) and r["method"] not in base:
            base[r["method"]] = sec["solve"] * r["ranks"]
        memory = rep.get("memory", {}).get("peak_rss_bytes_total")
        tets = elements(rep)
        row = {
            "mesh": os.path.basename(mesh), "elements": tets, "method": r["method"], "ranks": r["ranks"],
            "iterations": rep["iterations"], "termination": rep["termination"],
            "read_s": sec.get("read"), "partition_s": sec.get("partition"), "distribute_s": sec.get("distribute"),
            "schedule_s": sec.get("schedule"), "solve_s": sec["solve"], "s_per_iteration": sec["solve"] / iterations,
            "efficiency": base[r["method"]] / (r["ranks"] * sec["solve"]) if r["method"] in base and sec["solve"] > 0 else None,
            "ghost_copies": par["ghost_copies"] if par else None, "messages": par["messages_per_exchange"] if par else None,
            "colors": par["colors"] if par else None,
            "worst_before": rep["worst_before"], "worst_after": rep["worst_after"],
            "mean_before": mean(rep, "before"), "mean_after": mean(rep, "after"),
            "inverted_before": rep["inverted_before"], "inverted_after": rep["inverted_after"],
            "peak_memory_bytes": memory,
            "bytes_per_element": memory / tets if memory and tets else None,
        }
        rows.append(row)

with open(os.path.join(args.out, "results.json"), "w") as f:
    json.dump(results, f, indent=1)
with open(os.path.join(args.out, "results.csv"), "w", newline="") as f:
    writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()) if rows else ["mesh"])
    writer.writeheader()
    writer.writerows(rows)
with open(os.path.join(args.out, "partitions.csv"), "w", newline="") as f:
    fields = ["mesh", "parts", "shared_vertices", "ghost_copies", "process_edges", "max_neighbours", "colors",
              "largest_part_elements", "metis_seconds"]
    writer = csv.DictWriter(f, fieldnames=fields)
    writer.writeheader()
    for mesh, entry in results["meshes"].items():
        for p in entry.get("partitions", []):
            writer.writerow({"mesh": os.path.basename(mesh), **{k: p[k] for k in fields[1:]}})


def fmt(value, digits=3):
    if value is None:
        return ""
    return f"{value:.{digits}f}" if isinstance(value, float) else str(value)


with open(os.path.join(args.out, "report.md"), "w") as f:
    f.write(f"Made by `python3 examples/study.py {' '.join(sys.argv[1:])}`.\n\n")
    f.write("| mesh | elements | method | ranks | iterations | read s | partition s | distribute s | schedule s | "
            "solve s | s/iteration | efficiency | ghost copies | messages | colors | worst before | worst after | "
            "inverted before | inverted after | peak memory MB | bytes/element |\n")
    f.write("|" + "---|" * 21 + "\n")
    for r in rows:
        memory = r["peak_memory_bytes"] / 2**20 if r["peak_memory_bytes"] else None
        f.write(f"| {r['mesh']} | {fmt(r['elements'])} | {r['method']} | {r['ranks']} | {r['iterations']} | "
                f"{fmt(r['read_s'], 2)} | {fmt(r['partition_s'], 2)} | {fmt(r['distribute_s'], 2)} | "
                f"{fmt(r['schedule_s'], 3)} | {fmt(r['solve_s'], 2)} | {fmt(r['s_per_iteration'], 3)} | "
                f"{fmt(r['efficiency'], 2)} | {fmt(r['ghost_copies'])} | {fmt(r['messages'])} | {fmt(r['colors'])} | "
                f"{fmt(r['worst_before'], 4)} | {fmt(r['worst_after'], 4)} | {r['inverted_before']} | "
                f"{r['inverted_after']} | {fmt(memory, 0)} | {fmt(r['bytes_per_element'], 0)} |\n")
    f.write("\n| mesh | parts | shared vertices | ghost copies | process edges | most neighbours | colors |\n")
    f.write("|---|---|---|---|---|---|---|\n")
    for mesh, entry in results["meshes"].items():
        for p in entry.get("partitions", []):
            f.write(f"| {os.path.basename(mesh)} | {p['parts']} | {p['shared_vertices']} | {p['ghost_copies']} | "
                    f"{p['process_edges']} | {p['max_neighbours']} | {p['colors']} |\n")

try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print("study.py: matplotlib is missing (apt-get install python3-matplotlib); tables written, no plots",
          file=sys.stderr)
    sys.exit(0)

meshes = list(results["meshes"])
# Worst and mean quality per iteration, one process (Figs. 2 and 4).
fig, axes = plt.subplots(len(meshes), 2, figsize=(11, 3.6 * len(meshes)), squeeze=False)
for row, mesh in enumerate(meshes):
    for r in results["meshes"][mesh]["runs"]:
        if r["ranks"] != min(args.ranks) and r["method"] in DISTRIBUTED:
            continue
        history = r["report"]["history"]
        if not history:
            continue
        x = [h["iteration"] for h in history]
        axes[row][0].plot(x, [h["worst_quality"] for h in history], label=r["method"])
        axes[row][1].plot(x, [h["mean_quality"] for h in history], label=r["method"])
    for col, what in enumerate(("worst", "mean")):
        axes[row][col].set_title(f"{os.path.basename(mesh)}: {what} quality")
        axes[row][col].set_xlabel("iteration (sweep)")
        axes[row][col].legend()
fig.tight_layout()
fig.savefig(os.path.join(args.out, "quality.png"), dpi=110)

# Solve time per iteration and strong-scaling efficiency per process count (Figs. 3, 5, 6).
fig, axes = plt.subplots(1, 2, figsize=(11, 3.8))
for r_method in DISTRIBUTED:
    for mesh in meshes:
        mine = [r for r in rows if r["method"] == r_method and r["mesh"] == os.path.basename(mesh)]
        if not mine:
            continue
        label = f"{r_method}, {os.path.basename(mesh)}"
        axes[0].plot([r["ranks"] for r in mine], [r["s_per_iteration"] for r in mine], "o-", label=label)
        axes[1].plot([r["ranks"] for r in mine], [r["efficiency"] for r in mine], "o-", label=label)
axes[0].set_title("solve time per iteration (s)")
axes[1].set_title("strong-scaling efficiency T1 / (p Tp)")
for ax in axes:
    ax.set_xlabel("processes")
    ax.legend()
fig.tight_layout()
fig.savefig(os.path.join(args.out, "scaling.png"), dpi=110)

# Initialization by stage (Table 1), global solver runs.
stages = ("read_s", "partition_s", "distribute_s", "schedule_s")
init = [r for r in rows if r["method"] == "global"]
if init:
    fig, ax = plt.subplots(figsize=(7, 3.8))
    bottom = [0.0] * len(init)
    labels = [f"{r['mesh']}\n{r['ranks']} proc." for r in init]
    for stage in stages:
        values = [r[stage] or 0.0 for r in init]
        ax.bar(labels, values, bottom=bottom, label=stage[:-2])
        bottom = [b + v for b, v in zip(bottom, values)]
    ax.set_ylabel("seconds")
    ax.set_title("initialization by stage")
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "initialization.png"), dpi=110)

# Communicated vertices per partition count (Table 2).
if any(results["meshes"][m].get("partitions") for m in meshes):
    fig, ax = plt.subplots(figsize=(7, 3.8))
    for mesh in meshes:
        parts = results["meshes"][mesh].get("partitions", [])
        ax.plot([p["parts"] for p in parts], [p["shared_vertices"] for p in parts], "o-", label=os.path.basename(mesh))
    ax.set_xscale("log", base=2)
    ax.set_xlabel("partitions")
    ax.set_ylabel("vertices whose gradients are communicated")
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "partitions.png"), dpi=110)
print(f"study.py: wrote {args.out}/results.csv, results.json, partitions.csv, report.md and plots", file=sys.stderr)
