#!/usr/bin/env python3
"""When a run's best worst quality first reached given levels, and where its phases began and
ended: read from the history of `paloverde improve ... --summary s.json` (issue 16's tables of
"iterations to a level" in docs/global_solver.md). Run by hand, like the other benchmarks.

    python3 tests/perf/history_levels.py SUMMARY.json... --levels 0.15,0.17,0.19 [--phases]

Iterations are exact from run to run; seconds are solver seconds and move with the machine.
"""
import argparse
import json

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("summaries", nargs="+")
parser.add_argument("--levels", default="", help="comma-separated worst qualities")
parser.add_argument("--phases", action="store_true", help="also list each phase's iterations, seconds and best worst")
args = parser.parse_args()
levels = [float(x) for x in args.levels.split(",") if x]


def history_of(path):
    with open(path) as f:
        summary = json.load(f)
    # A queue's steps run one after another; their histories continue each other.
    return summary, [r for step in summary["steps"] for r in step["summary"]["history"]]


print("| summary | final worst | iterations | " + " | ".join(str(level) for level in levels) + " |")
print("|---|---|---|" + "---|" * len(levels))
for path in args.summaries:
    summary, history = history_of(path)
    cells = []
    for level in levels:
        hit = next((r for r in history if r["best_worst_quality"] >= level), None)
        cells.append("it %d, %.2f s" % (hit["iteration"], hit["seconds"]) if hit else "-")
    print("| %s | %.7f | %d | %s |" % (path, summary["worst_after"], summary["iterations"], " | ".join(cells)))
    if args.phases:
        phases = []
        for r in history:
            if not phases or phases[-1]["phase"] != r["phase"]:
                phases.append({"phase": r["phase"], "first": r, "last": r})
            phases[-1]["last"] = r
        for p in phases:
            print("    %-13s iterations %d-%d, %.2f-%.2f s, best worst %.8f" %
                  (p["phase"], p["first"]["iteration"], p["last"]["iteration"], p["first"]["seconds"],
                   p["last"]["seconds"], p["last"]["best_worst_quality"]))
