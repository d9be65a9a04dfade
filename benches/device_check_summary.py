"""Writes summary.md for a device-check.sh results folder: the machine, every step with its
command and status, and every figure the steps measured. Standard library only.

    python3 benches/device_check_summary.py DIR QUICK
"""

import csv
import json
import os
import re
import sys


def read(path):
    try:
        with open(path) as f:
            return f.read()
    except OSError:
        return ""


def section(text, title):
    """The lines under `## title` in machine.txt, up to the next `## `."""
    m = re.search(r"^## " + re.escape(title) + r"\n(.*?)(?=^## |\Z)", text, re.S | re.M)
    return m.group(1).strip() if m else ""


def machine(out):
    text = read(os.path.join(out, "machine.txt"))
    lines = []
    gpus = section(text, "nvidia-smi --query-gpu").splitlines()[1:]
    for g in gpus:
        lines.append(f"- GPU: {g.strip()} (name, driver, memory; nvidia-smi)")
    for line in section(text, "drapekit info").splitlines():
        if line.startswith(("adapter:", "--adapter auto picks", "cpu:", "cpu threads")):
            lines.append(f"- drapekit info: `{line.strip()}`")
    cpu = section(text, "lscpu")
    model = re.search(r"^Model name:\s*(.+)$", cpu, re.M)
    if model:
        lines.append(f"- CPU: {model.group(1).strip()}, {section(text, 'nproc')} cores (nproc)")
    version = section(text, "drapekit --version")
    if version:
        lines.append(f"- {version}")
    return lines


def steps(out):
    with open(os.path.join(out, "steps.tsv")) as f:
        return list(csv.DictReader(f, delimiter="\t"))


def rows(path):
    try:
        with open(path) as f:
            return list(csv.DictReader(f))
    except OSError:
        return []


def table(header, body):
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in body]
    return lines


def sci(x):
    try:
        return f"{float(x):.3g}"
    except (TypeError, ValueError):
        return "—"


def shirts(out, by_name):
    body = []
    for name in ("shirt_cotton_gpu", "shirt_cotton_cpu", "shirt_hires_gpu"):
        s = by_name.get(name)
        if s is None:
            continue
        try:
            with open(os.path.join(out, name, "summary.json")) as f:
                d = json.load(f)
        except (OSError, ValueError):
            body.append([name, s["status"], s["seconds"], "—", "—", "—", "—", "—", "—", f"`{s['command']}`"])
            continue
        device = d.get("adapter") or f"CPU, {d.get('cpu_threads')} threads"
        if isinstance(device, dict):
            device = device.get("name", str(device))
        sdf = d.get("sdf") or {}
        body.append(
            [
                name,
                s["status"],
                s["seconds"],
                f"{d.get('backend')} ({device})",
                d.get("particles"),
                d.get("frames"),
                f"{d.get('wall_seconds', 0):.2f}",
                sci(d.get("particle_substeps_per_second")),
                f"{sdf.get('bake_seconds', 0):.1f}",
                f"`{s['command']}`",
            ]
        )
    header = ["run", "status", "step wall s", "backend", "particles", "frames", "sim wall s",
              "particle-substeps/s", "SDF bake s", "command"]
    return table(header, body)


def bench(out, by_name):
    runs = [("bench", "drapekit's choice"), ("bench_layout_textures", "textures"),
            ("bench_layout_buffers", "buffers")]
    data = {label: rows(os.path.join(out, name, "bench.csv")) for name, label in runs}
    keys = []
    for label, rs in data.items():
        for r in rs:
            k = (int(r["size"]), r["backend"])
            if k not in keys:
                keys.append(k)
    body = []
    for size, backend in sorted(keys):
        cells = [f"{size}²", backend]
        device = ""
        for label, rs in data.items():
            r = next((r for r in rs if int(r["size"]) == size and r["backend"] == backend), None)
            cells.append(sci(r["particle_substeps_per_second"]) if r else "—")
            device = device or (r["device"] if r else "")
        body.append(cells + [device])
    header = ["grid", "backend"] + [f"DRAPEKIT_GPU_LAYOUT: {label}" for _, label in runs] + ["device"]
    lines = ["Particle-substeps per second (springs + bending, whole substeps).", ""]
    lines += table(header, body)
    lines += [""] + [f"- {label}: `{by_name[n]['command']}` ({by_name[n]['status']})"
                     for n, label in runs if n in by_name]
    return lines


def peer(out, name, by_name):
    rs = rows(os.path.join(out, name, "peer.csv"))
    body = [[r["system"], r["backend"], r["integrator"], f"{r['grid']}²", sci(r["particle_substeps_per_s"]),
             r["substeps_per_frame"], r["iterations"], r["device"]] for r in rs]
    header = ["system", "backend", "integrator", "grid", "particle-substeps/s", "substeps/frame",
              "sweeps", "device"]
    lines = table(header, body)
    if name in by_name:
        lines += ["", f"Command: `{by_name[name]['command']}` ({by_name[name]['status']})"]
    return lines


def threads(out, by_name):
    names = sorted((n for n in by_name if n.startswith("threads_")), key=lambda n: int(n.split("_")[1]))
    per = {}
    for n in names:
        for r in rows(os.path.join(out, n, "peer.csv")):
            if r["system"] == "drapekit" and r["backend"] == "cpu" and r["integrator"] == "implicit":
                per.setdefault(int(r["grid"]), {})[int(n.split("_")[1])] = float(r["particle_substeps_per_s"])
    body = []
    for grid, by_t in sorted(per.items()):
        base = by_t.get(1)
        for t, v in sorted(by_t.items()):
            speedup = f"{v / base:.2f}×" if base else "—"
            body.append([f"{grid}²", t, sci(v), speedup])
    lines = ["The CPU's implicit rows of `bench peer`, by `--threads` (speed-up against 1 thread).", ""]
    lines += table(["grid", "threads", "particle-substeps/s", "speed-up"], body)
    lines += [""] + [f"- `{by_name[n]['command']}` ({by_name[n]['status']})" for n in names]
    return lines


def profile(out, by_name):
    """Each case's GPU and wall time per substep and its costliest stage; profile.md has all."""
    rs = rows(os.path.join(out, "profile", "profile.csv"))
    if not rs:
        return [f"No profile ({by_name.get('profile', {}).get('status', 'not run')})."]
    cases = {}
    for r in rs:
        c = cases.setdefault(r["case"], r)
        if float(r["share"]) > float(c["share"]):
            cases[r["case"]] = r
    body = [[c, r["particles"], r["gpu_us_per_substep"], r["wall_us_per_substep"],
             f"{r['stage']} ({float(r['share']):.0f}%)"] for c, r in cases.items()]
    lines = table(["case", "particles", "GPU µs/substep", "wall µs/substep", "costliest stage"], body)
    return lines + ["", "Every stage: profile/profile.md.", "", f"- `{by_name['profile']['command']}`"]


def main():
    out, quick = sys.argv[1], sys.argv[2] == "1"
    all_steps = steps(out)
    by_name = {s["step"]: s for s in all_steps}
    passed = sum(s["status"] == "ok" for s in all_steps)
    lines = ["# drapekit device check" + (" (--quick)" if quick else ""), ""]
    lines += ["## Machine", ""] + machine(out) + ["", "Full details: machine.txt.", ""]
    lines += ["## Steps", "", f"{passed} of {len(all_steps)} steps passed; each step's output is in logs/.", ""]
    lines += table(["step", "status", "wall s", "command"],
                   [[s["step"], s["status"], s["seconds"], f"`{s['command']}`"] for s in all_steps])
    lines += ["", "## Garments", ""] + shirts(out, by_name)
    lines += ["", "## Substeps by grid size and GPU memory layout", ""] + bench(out, by_name)
    lines += ["", "## Where the GPU's time goes (`bench profile`)", ""] + profile(out, by_name)
    lines += ["", "## drapekit on Warp's benchmark cloth (`bench peer`)", ""] + peer(out, "peer", by_name)
    lines += ["", "## CPU thread scaling of implicit Euler", ""] + threads(out, by_name)
    if os.path.exists(os.path.join(out, "peers", "peer.csv")) or "peers" in by_name:
        lines += ["", "## drapekit beside Warp and Newton", ""] + peer(out, "peers", by_name)
    path = os.path.join(out, "summary.md")
    with open(path + ".tmp", "w") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(path + ".tmp", path)


if __name__ == "__main__":
    main()
