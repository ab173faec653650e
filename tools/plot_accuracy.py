#!/usr/bin/env python3
"""Speed against error for `cstreams accuracy`: reads its JSON, writes a PNG.

Left: false positives against nanoseconds per query, one point per solver setting
(tolerance sweeps join into curves); right: the largest time-of-impact error against
the same time. Totals are over every dataset of a kind; false negatives are printed in
the legend so a curve that misses contacts cannot pass for a fast one. With several
devices (`--devices`) each device gets its own curves, named in the legend; a device
that does not time kernels (no ns per query) is left out and named below the plot.
usage: plot_accuracy.py RESULTS.json OUT.png
"""
import collections
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(source, target):
    data = json.load(open(source))
    series = collections.defaultdict(lambda: collections.defaultdict(lambda: [0, 0, 0, 0.0, 0.0, 0]))
    several = len(data.get("devices", [])) > 1
    untimed = sorted({r.get("device", "?") for r in data["results"] if r["ns_per_query"] is None})
    for r in data["results"]:
        if r["ns_per_query"] is None:
            continue
        key = (r.get("device", "") if several else "", r["kind"], r["solver"], r["precision"])
        point = series[key][r["tolerance"]]
        point[0] += r["queries"]
        point[1] += r["false_positives"]
        point[2] += r["false_negatives"]
        point[3] += r["ns_per_query"] * r["queries"]
        point[4] = max(point[4], r["toi_error_max"] or 0.0)
        point[5] += r.get("toi_known", 0)
    fig, (left, right) = plt.subplots(1, 2, figsize=(13, 5))
    for (device, kind, solver, precision), points in sorted(series.items()):
        tolerances = sorted(points)
        ns = [points[t][3] / max(points[t][0], 1) for t in tolerances]
        fp = [max(points[t][1], 0.5) for t in tolerances]
        timed = [t for t in tolerances if points[t][5] > 0]
        fn = sum(points[t][2] for t in tolerances)
        label = f"{device + ': ' if device else ''}{kind} {solver} {precision} (false negatives: {fn})"
        left.plot(ns, fp, marker="o", label=label)
        if timed:
            right.plot([points[t][3] / max(points[t][0], 1) for t in timed],
                       [max(points[t][4], 1e-18) for t in timed], marker="o", label=label)
        for t, x, y in zip(tolerances, ns, fp):
            left.annotate(f"{t:g}", (x, y), fontsize=7, xytext=(3, 3), textcoords="offset points")
    for ax, title, ylabel in ((left, "false positives", "false positives (0 drawn at 0.5)"),
                              (right, "time-of-impact error", "max |toi - exact toi|")):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("ns per query" if several else "ns per query on " + data.get("device", "?"))
        ax.set_ylabel(ylabel)
        ax.set_title(title)
        ax.grid(True, which="both", alpha=0.3)
    left.legend(fontsize=7)
    if not right.lines:
        right.text(0.5, 0.5, "no exact times of impact in these datasets", ha="center", transform=right.transAxes)
    if untimed:
        fig.text(0.01, 0.01, "not drawn (does not time kernels): " + ", ".join(untimed), fontsize=8)
    fig.tight_layout(rect=(0, 0.04 if untimed else 0, 1, 1))
    fig.savefig(target, dpi=120)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
