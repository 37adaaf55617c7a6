"""Draw a learning curve from the CSV log of examples/ppo_train.py (`--log FILE.csv`): mean episode
return and success rate per epoch against environment steps, one line per CSV, with optional
horizontal reference lines (a random policy's return, the scripted expert's, ...).

    python examples/plot_learning_curve.py ppo.csv --out curve.png \\
        --title "PPO on IIWA/box/no_obstacle/pick_place" \\
        --return-line 0.95 "uniform random policy"

Needs matplotlib (`pip install composuite_ros[plots]`, or `pip install matplotlib`).
"""

from __future__ import annotations

import argparse
import csv
import sys
from pathlib import Path


def read_log(path: Path) -> dict[str, list[float]]:
    """The columns the plot needs, epochs in order; epochs with no finished episode are skipped
    (their return and success cells are empty)."""
    steps, returns, success = [], [], []
    with path.open(newline="") as f:
        reader = csv.DictReader(f)
        missing = {"total_steps", "ep_return_mean", "success_rate"} - set(reader.fieldnames or [])
        if missing:
            raise SystemExit(f"{path}: not a ppo_train.py log (no column {', '.join(sorted(missing))})")
        for row in reader:
            if row["ep_return_mean"] == "":
                continue
            steps.append(float(row["total_steps"]))
            returns.append(float(row["ep_return_mean"]))
            success.append(float(row["success_rate"]) if row["success_rate"] != "" else float("nan"))
    if not steps:
        raise SystemExit(f"{path}: no epoch with a finished episode yet")
    return {"steps": steps, "return": returns, "success": success}


def plot(logs: dict[str, dict[str, list[float]]], out: Path, title: str,
         return_lines: list[tuple[float, str]]) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ret_ax, succ_ax) = plt.subplots(2, 1, figsize=(8, 6), sharex=True,
                                          gridspec_kw={"height_ratios": [3, 2]})
    for label, log in logs.items():
        millions = [s / 1e6 for s in log["steps"]]
        ret_ax.plot(millions, log["return"], label=label)
        succ_ax.plot(millions, log["success"], label=label)
    for value, label in return_lines:
        ret_ax.axhline(value, linestyle="--", color="grey", linewidth=1)
        ret_ax.annotate(label, xy=(0, value), xycoords=("axes fraction", "data"),
                        xytext=(4, 3), textcoords="offset points", fontsize=8, color="dimgrey")
    ret_ax.set_ylabel("mean episode return")
    succ_ax.set_ylabel("success rate")
    succ_ax.set_ylim(-0.02, 1.02)
    succ_ax.set_xlabel("environment steps (millions)")
    ret_ax.set_title(title)
    for ax in (ret_ax, succ_ax):
        ax.grid(alpha=0.3)
    if len(logs) > 1:
        ret_ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    plt.close(fig)


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("logs", nargs="+", type=Path, metavar="LOG.csv", help="ppo_train.py --log files")
    p.add_argument("--out", type=Path, required=True, metavar="PNG")
    p.add_argument("--title", default="PPO learning curve")
    p.add_argument("--label", action="append", default=[], metavar="NAME",
                   help="the legend name of each log, in their order (default: the file names)")
    p.add_argument("--return-line", nargs=2, action="append", default=[], metavar=("VALUE", "LABEL"),
                   help="a horizontal line on the return axis (repeatable)")
    args = p.parse_args(argv)
    lines = []
    for value, label in args.return_line:
        try:
            lines.append((float(value), label))
        except ValueError:
            p.error(f"--return-line {value!r}: not a number")
    if args.label and len(args.label) != len(args.logs):
        p.error(f"{len(args.label)} --label for {len(args.logs)} logs: give one per log, or none")
    labels = args.label or [path.stem for path in args.logs]
    logs = {label: read_log(path) for label, path in zip(labels, args.logs)}
    try:
        plot(logs, args.out, args.title, lines)
    except ImportError:
        sys.exit("plot_learning_curve.py needs matplotlib: pip install matplotlib")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
