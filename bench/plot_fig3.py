#!/usr/bin/python3
"""The paper's Figure 3 remade (Sato, Savchenko, Ohbuchi, Cyberworlds 2004): update rate
(updates per second, log scale) against the support radius R for the four Table 1 meshes
(1089, 4225, 16641, 33025 vertices), anchored and unanchored, our measured rates beside the
paper's. Reads the JSON lines of `facepuppet bench --case table1 --json` (other lines and
cases are ignored) from --in FILE or stdin; writes a PNG with matplotlib (Debian's
python3-matplotlib). `facepuppet bench --plot FILE.png` runs the bench and this script.

Usage: plot_fig3.py --out FILE.png [--in FILE.jsonl] [--title TEXT]
       plot_fig3.py --check     exit 0 when matplotlib can be imported, else 3 (a message)
Exit status: 0 written, 2 usage, 3 matplotlib missing, 65 no usable table1 rows in the input.
The output is written as given (`facepuppet bench --plot` passes a temporary file and renames
it into place)."""
import argparse
import json
import math
import sys

EXIT_NO_MATPLOTLIB = 3
EXIT_DATAERR = 65


def load_rows(stream):
    """The table1 rows: {(mode, vertices): {radius: (ours_fps, paper_fps)}}."""
    rows = {}
    for lineno, line in enumerate(stream, 1):
        line = line.strip()
        if not line.startswith("{"):
            continue
        try:
            r = json.loads(line)
        except json.JSONDecodeError as e:
            raise ValueError(f"line {lineno}: not JSON: {e}") from None
        if r.get("case") != "table1":
            continue
        try:
            mode, nv, radius, ms = r["mode"], int(r["vertices"]), float(r["radius"]), r["ms_median"]
        except (KeyError, TypeError, ValueError) as e:
            raise ValueError(f"line {lineno}: table1 row without {e}") from None
        if mode not in ("anchored", "unanchored"):
            raise ValueError(f"line {lineno}: mode '{mode}' is neither anchored nor unanchored")
        if ms is None or not (float(ms) > 0 and math.isfinite(float(ms))):
            raise ValueError(f"line {lineno}: ms_median {ms!r} is not a positive number")
        paper = r.get("paper_fps")
        rows.setdefault((mode, nv), {})[radius] = (1000.0 / float(ms),
                                                    float(paper) if paper is not None else None)
    return rows


def plot(rows, out, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    meshes = sorted({nv for (_, nv) in rows})
    colors = dict(zip(meshes, plt.rcParams["axes.prop_cycle"].by_key()["color"]))
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.4), sharey=True, dpi=90)
    for ax, mode in zip(axes, ("anchored", "unanchored")):
        for nv in meshes:
            pts = rows.get((mode, nv))
            if not pts:
                continue
            rs = sorted(pts)
            ours = [pts[r][0] for r in rs]
            ax.plot(rs, ours, "-o", color=colors[nv], ms=5, lw=1.6, label=f"{nv} ours")
            pr = [r for r in rs if pts[r][1] is not None]
            if pr:
                ax.plot(pr, [pts[r][1] for r in pr], "--s", color=colors[nv], ms=5, lw=1.1,
                        mfc="none", label=f"{nv} paper")
        ax.set_yscale("log")
        ax.set_title(mode)
        ax.set_xlabel("support radius R (grid over 64 x 64)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("updates per second (log)")
    handles, labels = axes[0].get_legend_handles_labels()
    if not handles:
        handles, labels = axes[1].get_legend_handles_labels()
    fig.legend(handles, labels, loc="center right", fontsize=8, title="vertices",
               title_fontsize=8, frameon=False)
    fig.suptitle(title, fontsize=10)
    fig.text(0.01, 0.01, "paper: Athlon 64 3400+, display included; ours: set_end_points "
             "(+ set_start_points unanchored) + evaluate, median, 10 control vectors",
             fontsize=7, alpha=0.7)
    fig.tight_layout(rect=(0, 0.03, 0.86, 1))
    fig.savefig(out, format="png")
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", help="the PNG to write")
    ap.add_argument("--in", dest="inp", help="JSON lines (default: stdin)")
    ap.add_argument("--title", default="Figure 3 remade: CSRBF update rate against support "
                    "radius, facepuppet vs Sato et al. 2004")
    ap.add_argument("--check", action="store_true", help="only check that matplotlib imports")
    a = ap.parse_args()
    try:
        import matplotlib  # noqa: F401
    except ImportError as e:
        print(f"plot_fig3.py: matplotlib is missing ({e}); on Debian: apt-get install "
              f"python3-matplotlib (interpreter {sys.executable})", file=sys.stderr)
        return EXIT_NO_MATPLOTLIB
    if a.check:
        return 0
    if not a.out:
        ap.error("--out FILE.png is required")
    src = a.inp or "<stdin>"
    try:
        if a.inp:
            with open(a.inp, encoding="utf-8") as f:
                rows = load_rows(f)
        else:
            rows = load_rows(sys.stdin)
    except ValueError as e:
        print(f"plot_fig3.py: {src}: {e}", file=sys.stderr)
        return EXIT_DATAERR
    except OSError as e:
        print(f"plot_fig3.py: {src}: {e.strerror}", file=sys.stderr)
        return 66
    if not rows:
        print(f"plot_fig3.py: {src}: no table1 rows (run `facepuppet bench --case table1 "
              "--json`)", file=sys.stderr)
        return EXIT_DATAERR
    try:
        plot(rows, a.out, a.title)
    except OSError as e:
        print(f"plot_fig3.py: {a.out}: {e.strerror}", file=sys.stderr)
        return 73
    return 0


if __name__ == "__main__":
    sys.exit(main())
