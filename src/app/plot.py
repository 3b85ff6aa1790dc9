# usv-fdi plot: the paper's two figures from the JSON Lines records of `usv-fdi replay`.
#
#   Fig. 1 (estimate): each a_n of A-hat over time, or its error a_n - a_n_true when the
#     truth is given (--truth); the first converged and armed times marked.
#   Fig. 2 (signals): the windowed statistic J_N of each residual channel against its enter
#     threshold, the isolation confidences C_a and C_g, every latched-state change of a
#     fault marked, model-mismatch verdicts and (with --csv) the injected faults shaded.
#     Needs the replay's signal records (usv-fdi replay --signals S).
#
# The usv-fdi executable carries this file and runs it with python3 (src/app/cmd_plot.cpp);
# it also runs on its own: python3 src/app/plot.py --help. Exit codes as usv-fdi's: 1 no
# matplotlib, 3 input, 4 output, 64 command line.
import sys

# Run as `python3 -c`, the working directory would come first on the path: a json.py or
# matplotlib.py there must not be imported in place of the real ones.
sys.path = [p for p in sys.path if p not in ("", ".")]

import argparse  # noqa: E402
import csv  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import os  # noqa: E402

EXIT_FAILURE, EXIT_INPUT, EXIT_OUTPUT, EXIT_USAGE = 1, 3, 4, 64
SENSORS = ("accelerometer", "gyro")
COLOURS = {"accelerometer": "tab:blue", "gyro": "tab:orange", "unknown": "tab:purple"}
STATE_STYLE = {  # the latched states of an event: line colour, line style
    "raised": ("tab:red", "-"),
    "active_acknowledged": ("tab:red", ":"),
    "cleared": ("tab:green", "--"),
    "acknowledged": ("tab:gray", ":"),
}


def fail(code, message):
    print(f"usv-fdi: error: {message}", file=sys.stderr)
    sys.exit(code)


def number(value):
    """A record's number, NaN for null (the replay writes non-finite numbers as null)."""
    return float("nan") if value is None else float(value)


def is_number(value):
    """null, or a number a float holds (a 400-digit integer is not one)."""
    if value is None:
        return True
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        float(value)
    except OverflowError:
        return False
    return True


class Records:
    """The records of one replay, by type, checked field by field."""

    def __init__(self, path):
        self.path = path
        self.estimates, self.signals, self.events, self.mismatches = [], [], [], []
        self.summary = None
        try:
            f = open(path, encoding="utf-8")
        except OSError as e:
            fail(EXIT_INPUT, f"{path}: cannot be read: {e.strerror}")
        with f:
            try:
                for lineno, line in enumerate(f, 1):
                    if line.strip():
                        self.add(json.loads(line), lineno)
            except UnicodeDecodeError as e:
                fail(EXIT_INPUT, f"{path}: not UTF-8 text: {e.reason}")
            except json.JSONDecodeError as e:
                fail(EXIT_INPUT, f"{path}:{lineno}: not a JSON record: {e.msg} (column {e.colno})")
            except (RecursionError, OverflowError, ValueError) as e:
                fail(EXIT_INPUT, f"{path}:{lineno}: not a usable JSON record: {e}")
        if not self.estimates and not self.signals:
            fail(EXIT_INPUT, f"{path}: no estimate or signal record (is it the output of "
                 "usv-fdi replay?)")

    def need(self, record, lineno, field, check, what):
        if field not in record or not check(record[field]):
            got = json.dumps(record.get(field)) if field in record else "missing"
            fail(EXIT_INPUT, f"{self.path}:{lineno}: {record['type']} record: '{field}' "
                 f"must be {what}, got {got}")
        return record[field]

    def add(self, record, lineno):
        if not isinstance(record, dict) or not isinstance(record.get("type"), str):
            fail(EXIT_INPUT, f"{self.path}:{lineno}: not a replay record (a JSON object with "
                 "a \"type\")")
        kind = record["type"]
        pair = lambda x: isinstance(x, list) and len(x) == 2 and all(map(is_number, x))
        if kind == "estimate":
            self.need(record, lineno, "t", is_number, "a number")
            self.need(record, lineno, "a",
                      lambda x: isinstance(x, list) and len(x) == 4 and all(map(is_number, x)),
                      "an array of 4 numbers [a1, a2, a3, a4]")
            self.estimates.append(record)
        elif kind == "signal":
            for field in ("t", "c_a", "c_g"):
                self.need(record, lineno, field, is_number, "a number")
            for field in ("j", "threshold"):
                self.need(record, lineno, field, pair, "an array of 2 numbers [accelerometer, gyro]")
            self.signals.append(record)
        elif kind == "event":
            self.need(record, lineno, "stamp", is_number, "a number")
            self.need(record, lineno, "sensor", lambda x: isinstance(x, str) and x in COLOURS,
                      "accelerometer, gyro or unknown")
            self.need(record, lineno, "state", lambda x: isinstance(x, str), "a string")
            self.events.append(record)
        elif kind == "mismatch":
            self.need(record, lineno, "t", is_number, "a number")
            self.need(record, lineno, "active", lambda x: isinstance(x, bool), "true or false")
            self.mismatches.append(record)
        elif kind == "summary":
            self.summary = record
        # Other types (of later versions) are not drawn.


def fault_intervals(path):
    """[(sensor, t0, t1)] from a voyage CSV's fault_a / fault_g columns (a value while the
    simulator injects a fault on that sensor, empty otherwise)."""
    try:
        f = open(path, newline="", encoding="utf-8")
    except OSError as e:
        fail(EXIT_INPUT, f"{path}: cannot be read: {e.strerror}")
    with f:
        try:
            return csv_intervals(path, f)
        except UnicodeDecodeError as e:
            fail(EXIT_INPUT, f"{path}: not UTF-8 text: {e.reason}")
        except csv.Error as e:
            fail(EXIT_INPUT, f"{path}: not a CSV file: {e}")


def csv_intervals(path, f):
    """fault_intervals() of an open file (blank and # lines skipped, as replay does; the
    messages name the file's own line numbers)."""
    lineno = [0]

    def data_lines():
        for n, line in enumerate(f, 1):
            if line.strip() and not line.startswith("#"):
                lineno[0] = n
                yield line

    rows = csv.reader(data_lines())
    header = next(rows, None)
    if header is None or "t" not in header:
        fail(EXIT_INPUT, f"{path}:{lineno[0]}: column 't': required column missing from the "
             "header")
    it = header.index("t")
    columns = [(s, header.index(c)) for s, c in zip(SENSORS, ("fault_a", "fault_g"))
               if c in header]
    if not columns:
        fail(EXIT_INPUT, f"{path}:{lineno[0]}: no fault_a or fault_g column (a voyage of "
             "usv-fdi sim has them)")
    intervals = []
    start = {s: None for s, _ in columns}
    t = float("nan")
    for row in rows:
        try:
            t = float(row[it])
        except (ValueError, IndexError):
            fail(EXIT_INPUT, f"{path}:{lineno[0]}: column 't': not a number")
        for sensor, i in columns:
            active = i < len(row) and row[i].strip() not in ("", "nan", "NaN")
            if active and start[sensor] is None:
                start[sensor] = t
            elif not active and start[sensor] is not None:
                intervals.append((sensor, start[sensor], t))
                start[sensor] = None
    for sensor, t0 in start.items():
        if t0 is not None:
            intervals.append((sensor, t0, t))
    return intervals


def first_time(records, field):
    return next((number(r["t"]) for r in records if r.get(field) is True), None)


def mark_times(ax, est, signals):
    converged = first_time(est, "converged")
    armed = first_time(est, "armed")
    if armed is None:
        armed = first_time(signals, "armed")
    for t, label, style in ((converged, "converged", "--"), (armed, "armed", ":")):
        if t is not None:
            ax.axvline(t, color="black", linestyle=style, linewidth=0.8, label=label,
                       gid=f"time-{label}")


def robust_limits(ax, values):
    """Y limits that show the bulk of the curve (2nd to 98th percentile, widened by half),
    so that the transients of the first seconds do not flatten the rest; the axis label says
    when values are cut."""
    finite = sorted(x for x in values if math.isfinite(x))
    if len(finite) < 50:
        return
    lo, hi = finite[len(finite) // 50], finite[-1 - len(finite) // 50]
    pad = 0.5 * (hi - lo) if hi > lo else max(abs(hi), 1e-12)
    lo, hi = lo - pad, hi + pad
    if finite[0] < lo or finite[-1] > hi:
        ax.set_ylim(lo, hi)
        ax.text(0.01, 0.02, "(cut: transients beyond the axis)", transform=ax.transAxes,
                fontsize="x-small", color="gray")


def figure_estimate(rec, truth, title, out):
    import matplotlib.pyplot as plt
    t = [number(r["t"]) for r in rec.estimates]
    fig, axes = plt.subplots(2, 2, sharex=True, figsize=(10, 6.5))
    for n, ax in enumerate(axes.flat):
        a = [number(r["a"][n]) for r in rec.estimates]
        if truth is None:
            ax.plot(t, a, color="tab:blue", label=f"â{n + 1}", gid=f"a{n + 1}")
            ax.set_ylabel(f"â{n + 1}")
        else:
            ax.plot(t, [x - truth[n] for x in a], color="tab:blue",
                    label=f"ã{n + 1} = â{n + 1} − a{n + 1}", gid=f"error-a{n + 1}")
            ax.axhline(0.0, color="gray", linewidth=0.6)
            ax.set_ylabel(f"ã{n + 1}   (a{n + 1} = {truth[n]:.4g})")
        robust_limits(ax, [x - truth[n] for x in a] if truth is not None else a)
        mark_times(ax, rec.estimates, rec.signals)
        ax.grid(True, alpha=0.3)
        ax.legend(loc="upper right", fontsize="small")
    for ax in axes[1]:
        ax.set_xlabel("t [s]")
    fig.suptitle(title + (": estimation error of A" if truth is not None else ": Â over time"))
    fig.tight_layout()
    save(fig, out)


def figure_signals(rec, faults, title, out):
    import matplotlib.pyplot as plt
    sig = rec.signals
    t = [number(r["t"]) for r in sig]
    fig, axes = plt.subplots(3, 1, sharex=True, figsize=(10, 8.5))
    for k, (ax, sensor) in enumerate(zip(axes, SENSORS)):
        j = [number(r["j"][k]) for r in sig]
        thr = [number(r["threshold"][k]) for r in sig]
        ax.plot(t, j, color=COLOURS[sensor], linewidth=0.9, label=f"J_N ({sensor} channel)",
                gid=f"j-{sensor}")
        ax.plot(t, thr, color="black", linestyle="--", linewidth=0.9, label="threshold",
                gid=f"threshold-{sensor}")
        if any(x > 0 for x in j + thr if not math.isnan(x)):
            ax.set_yscale("log")
        ax.set_ylabel(f"J_N, {sensor}")
    axes[2].plot(t, [number(r["c_a"]) for r in sig], color=COLOURS["accelerometer"],
                 label="C_a", gid="c-accelerometer")
    axes[2].plot(t, [number(r["c_g"]) for r in sig], color=COLOURS["gyro"], label="C_g",
                 gid="c-gyro")
    axes[2].set_ylim(-0.05, 1.05)
    axes[2].set_ylabel("isolation confidence")
    axes[2].set_xlabel("t [s]")

    for n, (sensor, t0, t1) in enumerate(faults):
        for ax in (axes[SENSORS.index(sensor)], axes[2]):
            ax.axvspan(t0, t1, color=COLOURS[sensor], alpha=0.12, gid=f"fault-{sensor}-{n}",
                       label=f"{sensor} fault (injected)")
    begin = None
    spans = []
    for m in rec.mismatches:
        if m["active"] and begin is None:
            begin = number(m["t"])
        elif not m["active"] and begin is not None:
            spans.append((begin, number(m["t"])))
            begin = None
    if begin is not None:
        spans.append((begin, t[-1] if t else begin))
    for n, (t0, t1) in enumerate(spans):
        for ax in axes:
            ax.axvspan(t0, t1, facecolor="none", edgecolor="gray", hatch="//", linewidth=0,
                       gid=f"mismatch-{n}", label="model mismatch")
    for e in rec.events:
        colour, style = STATE_STYLE.get(e["state"], ("black", "-"))
        for ax in axes:
            ax.axvline(number(e["stamp"]), color=colour, linestyle=style, linewidth=1.0,
                       gid=f"event-{e['state']}-{e['sensor']}-{e.get('sequence', 0)}",
                       label=f"{e['state']} ({e['sensor']})")
        if e["state"] == "raised" and len(rec.events) <= 12:  # else the labels overlap
            axes[2].annotate(f"{e['sensor']} {e.get('kind', '')}",
                             (number(e["stamp"]), 1.0), textcoords="offset points",
                             xytext=(3, -12), fontsize="small", color=colour)
    for ax in axes:
        mark_times(ax, rec.estimates, sig)
        ax.grid(True, alpha=0.3)
    # Each panel's legend names its own curves and shading; the bottom one also the events and
    # the converged / armed times, which every panel marks alike.
    shared = ("raised", "active_acknowledged", "cleared", "acknowledged", "converged", "armed",
              "model mismatch")
    for ax in axes:
        handles, labels = ax.get_legend_handles_labels()
        unique = {}
        for h, label in zip(handles, labels):
            if ax is axes[-1] or not label.startswith(shared):
                unique.setdefault(label, h)
        if ax is axes[-1]:
            ax.legend(unique.values(), unique.keys(), loc="upper center", fontsize="x-small",
                      ncol=4, bbox_to_anchor=(0.5, -0.2))
        else:
            ax.legend(unique.values(), unique.keys(), loc="upper left", fontsize="x-small",
                      ncol=3, framealpha=0.8)
    fig.suptitle(title + ": fault signals")
    fig.tight_layout()
    save(fig, out)


def save(fig, out):
    import matplotlib.pyplot as plt
    try:
        fig.savefig(out, dpi=100)
    except OSError as e:
        fail(EXIT_OUTPUT, f"{out}: cannot be written: {e.strerror}")
    plt.close(fig)
    print(out)


def parse_truth(text):
    parts = text.split(",")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != 4 or not all(map(math.isfinite, values)):
        fail(EXIT_USAGE, f"--truth: need four finite numbers a1,a2,a3,a4 (A row-major), got "
             f"'{text}'")
    return values


class Arguments(argparse.ArgumentParser):
    def error(self, message):
        fail(EXIT_USAGE, f"usv-fdi plot: {message}")


def main():
    p = Arguments(prog="usv-fdi plot",
                  description="The paper's figures from the records of usv-fdi replay.")
    p.add_argument("--input", required=True)
    p.add_argument("--csv")
    p.add_argument("--truth")
    p.add_argument("--output", default=".")
    p.add_argument("--format", default="png", choices=("png", "svg"))
    p.add_argument("--title")
    a = p.parse_args()
    truth = parse_truth(a.truth) if a.truth is not None else None
    rec = Records(a.input)  # the input's mistakes are named even without matplotlib
    faults = fault_intervals(a.csv) if a.csv else []
    try:
        import matplotlib
        matplotlib.use("Agg")
        matplotlib.rcParams["svg.fonttype"] = "none"  # text stays text in an SVG
        matplotlib.rcParams["svg.hashsalt"] = "usv-fdi"  # the same records, the same SVG
        matplotlib.rcParams["text.parse_math"] = False  # a '$' in a title or kind is a '$'
        import matplotlib.pyplot  # noqa: F401
    except ImportError as e:
        fail(EXIT_FAILURE, f"usv-fdi plot needs matplotlib for {sys.executable} (Debian "
             f"package python3-matplotlib, scripts/packages.txt section [plot]; another "
             f"interpreter: USV_FDI_PYTHON): {e}")
    title = a.title or os.path.basename(a.input)
    try:
        os.makedirs(a.output, exist_ok=True)
    except OSError as e:
        fail(EXIT_OUTPUT, f"{a.output}: cannot create the directory: {e.strerror}")
    if rec.estimates:
        figure_estimate(rec, truth, title, os.path.join(a.output, f"fig1-estimate.{a.format}"))
    else:
        print(f"usv-fdi: warning: {a.input}: no estimate record: no Fig. 1", file=sys.stderr)
    if rec.signals:
        figure_signals(rec, faults, title, os.path.join(a.output, f"fig2-signals.{a.format}"))
    else:
        print(f"usv-fdi: warning: {a.input}: no signal record: no Fig. 2 (replay with "
              "--signals S writes them)", file=sys.stderr)


if __name__ == "__main__":
    try:
        main()
    except SystemExit:
        raise
    except Exception as e:  # anything unforeseen is named, never a traceback
        fail(EXIT_FAILURE, f"usv-fdi plot: {type(e).__name__}: {e}")
