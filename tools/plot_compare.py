#!/usr/bin/env python3
"""Device time per pass for `cstreams compare`: reads its JSON, writes a PNG.

One group of bars per pass (the passes that cost most on any device, slowest first)
and one bar per device, on a logarithmic axis so that a CPU and a GPU fit on one
picture; the title says whether the devices' contacts are identical. A device whose
profiling events do not time kernels (null times) has no bars; its legend gives its
wall time per step instead.
usage: plot_compare.py RESULTS.json OUT.png
"""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402

MOST_PASSES = 12


def main(source, target):
    data = json.load(open(source))
    devices = data["devices"]
    def ms(d, p):
        return d["passes"].get(p) or 0.0

    passes = sorted({p for d in devices for p in d["passes"]},
                    key=lambda p: -max(ms(d, p) for d in devices))[:MOST_PASSES]
    rows = ["whole step"] + passes
    height = 0.8 / len(devices)
    fig, ax = plt.subplots(figsize=(9, 0.45 * len(rows) * len(devices) + 1.5))
    handles = []
    for i, d in enumerate(devices):
        label = f'{d["filter"]}: {d["device"]}'
        if d["median_device_ms"] is None:
            label += f' (no kernel timer; {d["median_host_ms"]:.1f} ms wall a step)'
        values = [d["median_device_ms"]] + [d["passes"].get(p) for p in passes]
        timed = [(r + i * height, max(v, 1e-4)) for r, v in enumerate(values) if v is not None]
        color = f"C{i}"
        if timed:
            ax.barh([y for y, _ in timed], [v for _, v in timed], height=height, color=color)
        handles.append(Patch(color=color, label=label))
    ax.set_yticks([r + 0.4 - height / 2 for r in range(len(rows))])
    ax.set_yticklabels(rows)
    ax.invert_yaxis()
    ax.set_xscale("log")
    ax.set_xlabel("median device time, ms (log)")
    same = "identical contacts" if data["identical"] else f'{data["difference_count"]} contacts differ'
    ax.set_title(f'{data["scene"]}: {data["solver"]} solver, {data["precision"]}; {same}')
    ax.legend(handles=handles, loc="lower right", fontsize="small")
    fig.tight_layout()
    fig.savefig(target, dpi=110)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
