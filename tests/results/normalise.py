"""An experiment folder's results as text that two runs of the same plan share.

What may differ between two runs of the same plan is left out: timings,
memory, sizes, paths and the network the runs were hosted on. Everything
else of summary.json (checksums included) and every CSV file is kept, sorted
by key, one value per line, so that a difference reads as a line of a diff.

    normalise.py FOLDER  (prints the text)
"""
import csv
import json
import pathlib
import sys

# Keys whose values are timings, memory, sizes, paths or the host's network.
DROPPED = {
    "wall_seconds", "run_seconds", "peak_rss_kb", "log_bytes", "log_dir", "checkpoint", "network", "resume",
    "resume_in", "merged_from", "shard", "reused_from", "experiment_file", "afford_version", "folder",
    "transport", "steps_per_second", "cut",
}
DROPPED_COLUMNS = {"wall_seconds", "run_seconds", "log_dir", "checkpoint", "reused_from", "peak_rss_kb", "log_bytes"}


def flatten(value, path, out):
    if isinstance(value, dict):
        for key in sorted(value):
            if key not in DROPPED:
                flatten(value[key], f"{path}.{key}" if path else key, out)
    elif isinstance(value, list):
        for i, item in enumerate(value):
            flatten(item, f"{path}[{i}]", out)
    elif isinstance(value, float):
        out.append(f"{path} = {value:.12g}")
    else:
        out.append(f"{path} = {json.dumps(value)}")


def folder_text(folder):
    folder = pathlib.Path(folder)
    out = []
    for summary in sorted(folder.rglob("summary.json")):
        out.append(f"## {summary.relative_to(folder)}")
        flatten(json.loads(summary.read_text()), "", out)
    for table in sorted(folder.rglob("*.csv")):
        out.append(f"## {table.relative_to(folder)}")
        with table.open(newline="") as f:
            rows = list(csv.reader(f))
        if not rows:
            continue
        keep = [i for i, name in enumerate(rows[0]) if name not in DROPPED_COLUMNS]
        for row in rows:
            out.append(",".join(row[i] for i in keep if i < len(row)))
    return "\n".join(out) + "\n"


if __name__ == "__main__":
    sys.stdout.write(folder_text(sys.argv[1]))
