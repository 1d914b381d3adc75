"""The learning-curve picture of a training run, from its log.csv (needs matplotlib, the plot extra)."""

from __future__ import annotations

import csv
from pathlib import Path

__all__ = ["plot_learning_curve", "plot_predictor_curve"]


def plot_learning_curve(log_csv: Path, png: Path, strategy: str = "hier", kept: str | None = None) -> bool:
    """Validation steps per stage (deterministic, and sampled where logged), the kept stage marked, with the
    expert's agreement and gain on the way, or the training episodes' steps and return for a run without an
    expert, in a lower panel where the run logged any; returns False (writing nothing) where matplotlib is
    not installed."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    with open(log_csv, newline="") as f:
        rows = list(csv.DictReader(f))
    stages = [r["stage"] for r in rows]
    x = list(range(len(rows)))

    def col(name: str) -> list[float]:
        return [float(r[name]) if r.get(name) else float("nan") for r in rows]

    agreement = col("expert_agreement")
    expert = any(v == v for v in agreement)  # NaN is the only value unequal to itself
    lower = expert or any(v == v for v in col("steps_mean") + col("return_mean"))
    if lower:
        fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    else:  # the baseline alone, or stages that log no training episodes
        fig, ax1 = plt.subplots(1, 1, figsize=(7, 3.5))
    ax1.plot(x, col("val_steps_mean"), "o-", color="tab:blue", label="validation steps (mean, deterministic)")
    sampled = col("val_sampled_steps_mean")
    has_sampled = any(v == v for v in sampled)
    if has_sampled:
        ax1.plot(x, sampled, "D-", color="tab:orange", label="validation steps (mean, sampled)")
    start = "untrained start" if has_sampled else "heuristic start (hier-heuristic)"
    ax1.axhline(col("val_steps_mean")[0], color="grey", ls="--", lw=1, label=start)
    if kept in stages:
        k = stages.index(kept)
        ax1.plot([k], [col("val_steps_mean")[k]], "*", ms=16, color="gold", mec="black", label=f"kept: {kept}")
    ax1.set_ylabel("validation steps")
    ax1.legend(loc="upper right", fontsize=8)
    ax1.set_title(f"mrexplore train --strategy {strategy}: {len(rows)} stage{'s' * (len(rows) != 1)}, kept {kept}")
    if not lower:
        ax1.set_xticks(x, stages, rotation=30)
        fig.tight_layout()
        fig.savefig(png, dpi=110)
        plt.close(fig)
        return True
    if expert:
        ax2.plot(x, agreement, "s-", color="tab:green", label="expert agreement (training data)")
        ax2.set_ylabel("share")
        ax2.set_ylim(0, 1)
        ax3 = ax2.twinx()
        ax3.plot(x, col("expert_gain"), "^-", color="tab:red", label="expert gain over student (eq. 9 return)")
        ax3.set_ylabel("return")
    else:  # PPO alone: what the sampled training episodes did
        ax2.plot(x, col("steps_mean"), "s-", color="tab:green", label="training episodes: steps (sampled)")
        ax2.set_ylabel("steps")
        ax3 = ax2.twinx()
        ax3.plot(x, col("return_mean"), "^-", color="tab:red", label="training episodes: return")
        ax3.set_ylabel("return")
    lines = ax2.get_lines() + ax3.get_lines()
    ax2.legend(lines, [ln.get_label() for ln in lines], loc="lower right", fontsize=8)
    ax2.set_xticks(x, stages, rotation=30)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)
    return True


def plot_predictor_curve(log_csv: Path, png: Path, kept_epoch: int) -> bool:
    """The map predictor's run: training and validation loss per epoch (the kept epoch marked) above the
    validation accuracy and IoU of predicted free space; returns False (writing nothing) where matplotlib is
    not installed."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    with open(log_csv, newline="") as f:
        rows = list(csv.DictReader(f))
    x = [int(r["epoch"]) for r in rows]

    def col(name: str) -> list[float]:
        return [float(r[name]) for r in rows]

    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    ax1.plot(x, col("loss"), "o-", color="tab:grey", label="training crops")
    ax1.plot(x, col("val_loss"), "o-", color="tab:blue", label="validation beliefs")
    if kept_epoch in x:
        k = x.index(kept_epoch)
        ax1.plot([kept_epoch], [col("val_loss")[k]], "*", ms=16, color="gold", mec="black", label=f"kept: {kept_epoch}")
    ax1.set_ylabel("cross-entropy (unknown cells near a frontier)")
    ax1.legend(loc="upper right", fontsize=8)
    ax1.set_title(f"mrexplore train --target predictor: {len(rows)} epoch{'s' * (len(rows) != 1)}, kept {kept_epoch}")
    ax2.plot(x, col("val_accuracy"), "s-", color="tab:green", label="validation accuracy")
    ax2.plot(x, col("val_iou"), "^-", color="tab:red", label="validation IoU of free space")
    ax2.set_xlabel("epoch")
    ax2.set_ylabel("share")
    ax2.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)
    return True
