#!/usr/bin/env python3
"""A comparison study in one command: methods x meshes x process counts, as the seed paper's
tables and figures.

    python3 examples/study.py MESH [MESH ...] [--methods global local smart_laplace]
        [--ranks 1 2] [--iterations 40] [--partitions 2 4 8 16 32 64] [--out study]
        [--weak SURFACE.off --per-rank N]

For each mesh it runs:
  - `paloverde partition MESH -n PARTITIONS --json`: the communication of each split (Table 2);
  - every distributed method (global, local) on every process count, with
    `mpiexec -n P paloverde_parallel_benchmark MESH --method M --iterations N`: initialization
    by stage (Table 1), solve time and strong-scaling efficiency T1/(p Tp) (Figs. 3, 5, 6), the
    per-iteration history (Figs. 2, 4) and the peak memory of the ranks;
  - every serial method (smart_laplace, laplace) once, with `paloverde improve`.
With --weak (Table 3, weak scaling; MESH may then be left out) it also makes, for each process
count p, a mesh of about p x N tetrahedra with `tetgen -pq1.4a<bound>QF SURFACE.off` (the
volume bound fitted in a few tries; TetGen is deterministic, so the same arguments give the
same meshes, kept in OUT/weak/ for the next run) and runs the distributed methods on it with p
processes: weak efficiency T1/Tp, T the time per iteration.
It writes to OUT: results.json (everything), results.csv (one row per run), partitions.csv,
report.md (the tables) and the plots quality.png, scaling.png, initialization.png,
partitions.png and weak.png (python3-matplotlib). Launcher flags come from the build's
MPIEXEC_PREFLAGS. Runs of more than the machine's cores count communication and check results;
their times mean nothing.
"""
import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile

DISTRIBUTED = ("global", "local")
SERIAL = ("smart_laplace", "laplace")

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("meshes", nargs="*")
parser.add_argument("--methods", nargs="+", default=["global", "local", "smart_laplace"],
                    choices=DISTRIBUTED + SERIAL)
parser.add_argument("--ranks", nargs="+", type=int, default=[1, 2])
parser.add_argument("--iterations", type=int, default=40, help="iterations (sweeps for local and Laplace)")
parser.add_argument("--partitions", nargs="*", type=int, default=[2, 4, 8, 16, 32, 64])
parser.add_argument("--build", default=os.environ.get("PALOVERDE_BUILD_DIR", "build"))
parser.add_argument("--out", default="study")
parser.add_argument("--weak", metavar="SURFACE", help="weak scaling from this closed surface (OFF)")
parser.add_argument("--per-rank", type=int, default=500000, help="tets per process in the weak-scaling meshes")
args = parser.parse_args()

if any(p < 1 for p in args.ranks) or any(p < 2 for p in args.partitions) or args.iterations < 0:
    sys.exit("study.py: --ranks must be >= 1, --partitions >= 2 and --iterations >= 0")
if not args.meshes and not args.weak:
    sys.exit("study.py: give at least one mesh, or --weak SURFACE.off")
for mesh in args.meshes:
    if not os.path.isfile(mesh):
        sys.exit(f"study.py: no mesh file {mesh}")
weak_methods = [m for m in args.methods if m in DISTRIBUTED]
if args.weak:
    if not os.path.isfile(args.weak) or not args.weak.endswith(".off"):
        sys.exit(f"study.py: --weak needs a closed surface as an .off file (got {args.weak})")
    if args.per_rank < 1000:
        sys.exit("study.py: --per-rank must be >= 1000")
    if not weak_methods:
        sys.exit("study.py: --weak runs the distributed methods (global, local); --methods has none")
    if shutil.which("tetgen") is None:
        sys.exit("study.py: --weak needs tetgen (apt-get install tetgen; scripts/setup.sh installs it)")
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


def enclosed_volume(off):
    """The volume a closed OFF surface encloses (divergence theorem over fan triangles)."""
    words = open(off).read().split()
    if not words or words[0] != "OFF":
        sys.exit(f"study.py: {off} is not an OFF file")
    nv, nf = int(words[1]), int(words[2])
    xyz = [tuple(map(float, words[4 + 3 * i:7 + 3 * i])) for i in range(nv)]
    at, volume = 4 + 3 * nv, 0.0
    for _ in range(nf):
        k = int(words[at])
        f = [int(w) for w in words[at + 1:at + 1 + k]]
        at += 1 + k
        for i in range(1, k - 1):
            (ax, ay, az), (bx, by, bz), (cx, cy, cz) = xyz[f[0]], xyz[f[i]], xyz[f[i + 1]]
            volume += (ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)) / 6.0
    return abs(volume)


def weak_mesh(surface, target, folder):
    """A TetGen mesh of about `target` tets in `folder`: (its .node file, the volume bound).
    The bound is fitted to what TetGen gives, tets = F + C / bound (F: what the quality bound
    alone makes near the surface), until within 10%; a finished folder is reused."""
    os.makedirs(folder, exist_ok=True)
    off = os.path.join(folder, "surface.off")
    node, done = off[:-4] + ".1.node", os.path.join(folder, "bound")
    if os.path.isfile(done) and os.path.isfile(node):
        return node, open(done).read().strip()
    shutil.copyfile(surface, off)

    def tetgen(bound):
        subprocess.run(["tetgen", f"-pq1.4a{bound:.6g}QF", off], check=True, stdout=subprocess.DEVNULL)
        tets = int(open(off[:-4] + ".1.ele").readline().split()[0])
        print(f"  tetgen -pq1.4a{bound:.6g}QF: {tets} tets (target {target})", file=sys.stderr)
        return tets

    tries = []
    bound = enclosed_volume(off) / target * 2.5  # TetGen's tets average about 0.4 of the bound
    for _ in range(6):
        tries.append((bound, tetgen(bound)))
        if abs(tries[-1][1] - target) <= 0.1 * target:
            break
        if len(tries) == 1:
            bound *= tries[-1][1] / target
            continue
        (b0, n0), (b1, n1) = tries[-2], tries[-1]
        c = (n0 - n1) / (1 / b0 - 1 / b1) if b0 != b1 else 0.0
        floor = n1 - c / b1
        if c <= 0 or target <= floor * 1.05:
            print(f"  the surface alone gives about {int(floor)} tets with q1.4; ask for more per rank", file=sys.stderr)
            break
        bound = c / (target - floor)
    bound = min(tries, key=lambda t: abs(t[1] - target))[0]
    if tries[-1][0] != bound:
        tetgen(bound)  # the closest try is the mesh to run
    open(done, "w").write(f"{bound:.6g}\n")
    return node, f"{bound:.6g}"


preflags = mpiexec_preflags()
results = {"iterations": args.iterations, "meshes": {}, "weak": []}
os.makedirs(args.out, exist_ok=True)
if args.weak:
    for p in args.ranks:
        mesh, bound = weak_mesh(args.weak, p * args.per_rank, os.path.join(args.out, "weak", str(p)))
        for method in weak_methods:
            out = run(["mpiexec", "-n", str(p), *preflags, benchmark, mesh, "--method", method,
                       "--iterations", str(args.iterations)])
            results["weak"].append({"method": method, "ranks": p, "tetgen_bound": bound, "report": json.loads(out)})
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

weak_rows = []
for r in results["weak"]:
    rep = r["report"]
    per_iteration = rep["parallel"]["seconds"]["solve"] / max(1, rep["iterations"])
    base = next(w for w in results["weak"] if w["method"] == r["method"] and w["ranks"] == min(args.ranks))["report"]
    base_per_iteration = base["parallel"]["seconds"]["solve"] / max(1, base["iterations"])
    memory = rep.get("memory", {}).get("peak_rss_bytes_total")
    weak_rows.append({
        "method": r["method"], "ranks": r["ranks"], "tetgen_bound": r["tetgen_bound"], "elements": elements(rep),
        "elements_per_rank": elements(rep) // r["ranks"], "iterations": rep["iterations"],
        "solve_s": rep["parallel"]["seconds"]["solve"], "s_per_iteration": per_iteration,
        "weak_efficiency": base_per_iteration / per_iteration if per_iteration > 0 else None,
        "ghost_copies": rep["parallel"]["ghost_copies"], "messages": rep["parallel"]["messages_per_exchange"],
        "worst_before": rep["worst_before"], "worst_after": rep["worst_after"],
        "bytes_per_element": memory / elements(rep) if memory else None,
    })
if weak_rows:
    with open(os.path.join(args.out, "weak.csv"), "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(weak_rows[0].keys()))
        writer.writeheader()
        writer.writerows(weak_rows)

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
    if rows:
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
    if any(entry.get("partitions") for entry in results["meshes"].values()):
        f.write("\n| mesh | parts | shared vertices | ghost copies | process edges | most neighbours | colors |\n")
        f.write("|---|---|---|---|---|---|---|\n")
        for mesh, entry in results["meshes"].items():
            for p in entry.get("partitions", []):
                f.write(f"| {os.path.basename(mesh)} | {p['parts']} | {p['shared_vertices']} | {p['ghost_copies']} | "
                        f"{p['process_edges']} | {p['max_neighbours']} | {p['colors']} |\n")

    if weak_rows:
        f.write(f"\nWeak scaling from {os.path.basename(args.weak)}, about {args.per_rank:,} tets per process "
                "(efficiency T1/Tp, T the time per iteration):\n\n")
        f.write("| method | ranks | tetgen bound | elements | elements per rank | iterations | solve s | s/iteration | "
                "weak efficiency | ghost copies | messages | worst before | worst after | bytes/element |\n")
        f.write("|" + "---|" * 14 + "\n")
        for r in weak_rows:
            f.write(f"| {r['method']} | {r['ranks']} | {r['tetgen_bound']} | {r['elements']:,} | "
                    f"{r['elements_per_rank']:,} | {r['iterations']} | {fmt(r['solve_s'], 2)} | "
                    f"{fmt(r['s_per_iteration'], 3)} | {fmt(r['weak_efficiency'], 2)} | {r['ghost_copies']} | "
                    f"{r['messages']} | {fmt(r['worst_before'], 4)} | {fmt(r['worst_after'], 4)} | "
                    f"{fmt(r['bytes_per_element'], 0)} |\n")

try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print("study.py: matplotlib is missing (apt-get install python3-matplotlib); tables written, no plots",
          file=sys.stderr)
    sys.exit(0)



def per_process_plot(series, efficiency, time_title, efficiency_title, name):
    """Time per iteration and an efficiency against the process count: one line per (label, rows)."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.8))
    for label, mine in series:
        if not mine:
            continue
        axes[0].plot([r["ranks"] for r in mine], [r["s_per_iteration"] for r in mine], "o-", label=label)
        axes[1].plot([r["ranks"] for r in mine], [r[efficiency] for r in mine], "o-", label=label)
    axes[0].set_title(time_title)
    axes[1].set_title(efficiency_title)
    for ax in axes:
        ax.set_xlabel("processes")
        ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, name), dpi=110)


meshes = list(results["meshes"])
if meshes:
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
    series = [(f"{method}, {os.path.basename(mesh)}",
               [r for r in rows if r["method"] == method and r["mesh"] == os.path.basename(mesh)])
              for method in DISTRIBUTED for mesh in meshes]
    per_process_plot(series, "efficiency", "solve time per iteration (s)", "strong-scaling efficiency T1 / (p Tp)",
                     "scaling.png")

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
# Weak scaling (Table 3): time per iteration and efficiency against processes.
if weak_rows:
    per_process_plot([(method, [r for r in weak_rows if r["method"] == method]) for method in weak_methods],
                     "weak_efficiency", f"time per iteration, {args.per_rank:,} tets per process (s)",
                     "weak-scaling efficiency T1 / Tp", "weak.png")
print(f"study.py: wrote {args.out}/results.csv, results.json, partitions.csv, report.md and plots", file=sys.stderr)
