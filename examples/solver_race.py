#!/usr/bin/env python3
"""The global solver against the local smoother on the same meshes, one thread each: final worst
and mean quality, the solver's seconds, when each first reached its own final worst quality, and
when the global solver passed the local smoother's; and the default global solver once more with
the local smoother's worst quality as its target: the time to a result that is at least as good
as the local smoother's worst element, with its mean's polish (where the mean fell below the
input's) included in the time. With --old, the global solver as it was
before issue 16's focus, adaptive mu, finish and damped-vertex ascent (--set gain_tolerance=0,
focus_band=1, finish=none, damped_vertex_ascent=false) runs too; with --previous, as it was before
the Newton finish, the narrower focus and the damped-vertex ascent (finish=none, focus_band=0.05,
damped_vertex_ascent=false). Prints a markdown table (docs/global_solver.md, "Against
the local smoother"; its figures are kept in docs/data/race.csv) and, with matplotlib (Debian: python3-matplotlib), writes one plot per mesh of the best
worst quality against seconds.

    python3 examples/solver_race.py MESH [MESH ...] [--old] [--previous] [--plot PREFIX] [--set KEY=VALUE ...]
                                    [--paloverde build/bin/paloverde] [--threads 1] [--repeat 1] [--tolerance 0]

A level counts as reached within 1e-12, or within --tolerance times the level where that is
more: the local smoother's last sweeps often raise its worst quality in the tenth digit only
(fandisk-100k: 0.2183979824 after sweep 5 of 15), and with no relative tolerance its time to its
own result counts those sweeps.

--set passes options to the default global solver (queue[0].improve.KEY=VALUE), for sensitivity
runs; the local smoother and the old global solver ignore them.
"""
import argparse
import json
import os
import subprocess
import tempfile

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("meshes", nargs="+")
parser.add_argument("--paloverde", default="build/bin/paloverde")
parser.add_argument("--threads", default="1")
parser.add_argument("--old", action="store_true", help="also run the global solver with the old defaults")
parser.add_argument("--previous", action="store_true", help="also run the global solver without the finish, focus 0.05")
parser.add_argument("--plot", default=None, help="prefix of the PNG files written (one per mesh)")
parser.add_argument("--set", action="append", default=[], help="an option of the default global solver")
parser.add_argument("--repeat", type=int, default=1,
                    help="run each method this many times, in turns, and report the fastest (this machine's runs "
                         "move by up to a third from run to run; the results are the same every time)")
parser.add_argument("--tolerance", type=float, default=0.0,
                    help="relative tolerance within which a worst quality counts as reached (at least 1e-12 absolute)")
args = parser.parse_args()
if not args.tolerance >= 0.0:
    parser.error("--tolerance must be >= 0")

OLD = ["--set", "queue[0].improve.gain_tolerance=0", "--set", "queue[0].improve.focus_band=1", "--set",
       "queue[0].improve.finish=none", "--set", "queue[0].improve.damped_vertex_ascent=false"]
methods = [("global", ["--method", "global"] + [a for kv in args.set for a in ("--set", "queue[0].improve." + kv)])]
PREVIOUS = ["--set", "queue[0].improve.finish=none", "--set", "queue[0].improve.focus_band=0.05", "--set",
            "queue[0].improve.damped_vertex_ascent=false"]
if args.previous:
    methods.append(("previous global", ["--method", "global"] + PREVIOUS))
if args.old:
    methods.append(("old global", ["--method", "global"] + OLD))
methods.append(("local", ["--method", "local"]))


def run(mesh, extra, scratch):
    summary = os.path.join(scratch, "s.json")
    env = dict(os.environ, OMP_NUM_THREADS=args.threads)
    subprocess.run([args.paloverde, "improve", mesh, "-o", os.path.join(scratch, "out.vtu"), "--threads", args.threads,
                    "--summary", summary, "-q"] + extra, check=True, env=env)
    with open(summary) as f:
        s = json.load(f)
    return s


def reached(history, level):
    """Seconds at which the best worst quality first reached `level` (None: never)."""
    slack = max(1e-12, args.tolerance * abs(level))
    return next((r["seconds"] for r in history if r["best_worst_quality"] >= level - slack), None)


def fmt(seconds):
    return "-" if seconds is None else "%.2f" % seconds


print("| mesh | elements | input worst / mean | method | worst | mean | solver s | own worst at s | "
      "local's worst at s | iterations | stopped |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
with tempfile.TemporaryDirectory() as scratch:
    for mesh in args.meshes:
        runs = {name: [] for name, _ in methods}
        for _ in range(max(1, args.repeat)):
            for name, extra in methods:
                runs[name].append(run(mesh, extra, scratch))
        for name, tries in runs.items():
            if len({(t["worst_after"], t["iterations"]) for t in tries}) != 1:
                raise SystemExit("%s on %s: the repeated runs differ" % (name, mesh))
        local_worst = runs["local"][0]["worst_after"]
        # The default global solver stopped at the local smoother's worst (then its polish).
        targeted = [run(mesh, methods[0][1] + ["--target", repr(local_worst)], scratch) for _ in range(max(1, args.repeat))]
        if len({(t["worst_after"], t["iterations"]) for t in targeted}) != 1:
            raise SystemExit("global to local's worst on %s: the repeated runs differ" % mesh)
        curves = {}
        for name, _ in methods:
            tries = runs[name]
            histories = [[r for step_ in t["steps"] for r in step_["summary"]["history"]] for t in tries]
            # With --repeat, each time is the least over the runs; the plot shows the fastest run.
            fastest = min(range(len(tries)), key=lambda i: tries[i]["steps"][0]["summary"]["seconds"])
            s, step = tries[fastest], tries[fastest]["steps"][0]["summary"]
            curves[name] = histories[fastest]

            def least(level):
                times = [t for t in (reached(h, level) for h in histories) if t is not None]
                return min(times) if times else None

            before = step["before"]["metrics"][s["metric"]]
            print("| %s | %d | %.4f / %.4f | %s | %.6f | %.4f | %.2f | %s | %s | %d | %s |" % (
                os.path.basename(mesh), step["before"]["elements"], s["worst_before"], before["mean"], name,
                s["worst_after"], s["mean_after"], step["seconds"], fmt(least(s["worst_after"])),
                fmt(least(local_worst)), s["iterations"], step["message"]), flush=True)
        t = min(targeted, key=lambda t: t["steps"][0]["summary"]["seconds"])
        step = t["steps"][0]["summary"]
        print("| %s | %d | %.4f / %.4f | global to local's worst | %.6f | %.4f | %s | - | %s | %d | %s |" % (
            os.path.basename(mesh), step["before"]["elements"], t["worst_before"],
            step["before"]["metrics"][t["metric"]]["mean"], t["worst_after"], t["mean_after"], fmt(step["seconds"]),
            fmt(step["seconds"]), t["iterations"], step["message"]), flush=True)
        if args.plot:
            import matplotlib
            matplotlib.use("Agg")
            import matplotlib.pyplot as plt
            fig, ax = plt.subplots(figsize=(6, 4))
            for name, history in curves.items():
                ax.plot([r["seconds"] for r in history], [r["best_worst_quality"] for r in history], label=name)
            ax.set_xlabel("seconds (one thread)")
            ax.set_ylabel("worst quality (best so far)")
            ax.set_title(os.path.basename(mesh))
            ax.legend()
            fig.tight_layout()
            fig.savefig("%s-%s.png" % (args.plot, os.path.splitext(os.path.basename(mesh))[0]), dpi=90)
            plt.close(fig)
