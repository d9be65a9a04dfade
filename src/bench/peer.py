"""drapekit's driver for `drapekit bench peer`: times NVIDIA Warp's own cloth benchmark classes
and NVIDIA Newton's cloth solvers, from the installed wheels, on Warp's first CUDA device when
CUDA is there and on its CPU device otherwise (`--device cpu|cuda|auto`).

drapekit writes this file into its Python environment and runs it there. Nothing of Warp or
Newton is copied here: Warp's `Cloth` class and the benchmark's settings are read from the
installed `warp/examples/benchmarks/benchmark_cloth.py` (that file runs its whole benchmark and
imports `pxr` at import time, so only its `Cloth` class and the constants of `run_benchmark` are
taken from it), and `WpIntegrator` is imported from `benchmark_cloth_warp.py` as the benchmark
itself does.

Each measured point is printed on stdout as one line `PEER {json}`; everything else goes to
stderr. Commands:

    peer.py versions
    peer.py warp   --sizes 64,128 --frames 60 --state-dir DIR [--device auto|cpu|cuda]
    peer.py newton --solver semi_implicit|vbd --sizes 64 --frames 60 --substeps 16
                   [--iterations 10] --state-dir DIR [--device auto|cpu|cuda]
"""

import argparse
import ast
import json
import os
import statistics
import sys
import time


def emit(record):
    print("PEER " + json.dumps(record), flush=True)


def benchmarks_dir():
    import warp  # noqa: PLC0415

    return os.path.join(os.path.dirname(warp.__file__), "examples", "benchmarks")


def warp_benchmark(dim):
    """Warp's `Cloth` for a `dim`×`dim` grid and the settings `run_benchmark` uses with it,
    read from the installed benchmark file: the class definition is executed, and the
    function's top-level assignments are evaluated in order, `cloth = Cloth(...)` included."""
    import numpy as np  # noqa: PLC0415

    path = os.path.join(benchmarks_dir(), "benchmark_cloth.py")
    with open(path) as f:
        tree = ast.parse(f.read(), path)
    cloth_class = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "Cloth")
    run = next(n for n in tree.body if isinstance(n, ast.FunctionDef) and n.name == "run_benchmark")
    namespace = {"np": np}
    exec(compile(ast.Module(body=[cloth_class], type_ignores=[]), path, "exec"), namespace)
    settings = {"np": np, "Cloth": namespace["Cloth"], "dim": dim, "int": int, "float": float}
    cloth_call = None
    for stmt in run.body:
        if not (isinstance(stmt, ast.Assign) and all(isinstance(t, ast.Name) for t in stmt.targets)):
            continue
        if isinstance(stmt.value, ast.Call) and getattr(stmt.value.func, "id", None) == "Cloth":
            cloth_call = stmt.value
        value = eval(compile(ast.Expression(stmt.value), path, "eval"), settings)
        for t in stmt.targets:
            settings[t.id] = value
    if cloth_call is None:
        sys.exit(f"{path}: run_benchmark no longer builds a Cloth; this driver needs updating")
    cloth_args = {
        k.arg: eval(compile(ast.Expression(k.value), path, "eval"), settings) for k in cloth_call.keywords
    }
    return settings["cloth"], settings, cloth_args


def describe_cloth(cloth, settings, cloth_args):
    """What drapekit checks against its own copy of the cloth."""
    w = cloth.inv_masses
    return {
        "particles": int(cloth.num_particles),
        "springs": int(cloth.num_springs),
        "rest_length_sum": float(cloth.spring_lengths.astype("float64").sum()),
        "pinned": int((w == 0.0).sum()),
        "mass": float(cloth_args["mass"]),
        "spacing": float(cloth_args["radius"]),
        "stiffness": sorted({float(k) for k in cloth.spring_stiffness}),
        "damping": sorted({float(k) for k in cloth.spring_damping}),
        "fps": float(settings["sim_fps"]),
        "benchmark_substeps": int(settings["sim_substeps"]),
    }


def resolve_device(choice):
    """Warp's device for `choice`: "cuda" and "auto" (when CUDA is there) take "cuda:0"."""
    import warp as wp  # noqa: PLC0415

    if choice == "cpu" or (choice == "auto" and not wp.is_cuda_available()):
        return "cpu"
    if not wp.is_cuda_available():
        sys.exit("--device cuda: Warp finds no CUDA device (driver missing?); use --device cpu")
    return "cuda:0"


def device_record(device):
    """The device as the report names it."""
    import warp as wp  # noqa: PLC0415

    return {"device": device, "device_name": str(wp.get_device(device).name)}


def time_frames(frames, step):
    """Seconds of each of `frames` calls to `step()`."""
    times = []
    for _ in range(frames):
        start = time.perf_counter()
        step()
        times.append(time.perf_counter() - start)
    return times


def save_state(state_dir, name, positions):
    import numpy as np  # noqa: PLC0415

    path = os.path.join(state_dir, name)
    np.ascontiguousarray(positions, dtype="<f4").tofile(path)
    return path


def run_warp(args):
    import warp as wp  # noqa: PLC0415

    sys.path.insert(0, benchmarks_dir())
    import benchmark_cloth_warp  # noqa: PLC0415  (clears the kernel cache, as the benchmark does)

    device = resolve_device(args.device)
    for dim in args.sizes:
        cloth, settings, cloth_args = warp_benchmark(dim)
        integrator = benchmark_cloth_warp.WpIntegrator(cloth, device)
        # Compile the kernels before the clock starts (the benchmark's own warm-up is dead code).
        wp.load_module(benchmark_cloth_warp, device=device)
        frame_dt, substeps = settings["sim_dt"], settings["sim_substeps"]
        positions = []

        def step():
            positions.append(integrator.simulate(frame_dt, substeps))

        times = time_frames(args.frames, step)
        record = describe_cloth(cloth, settings, cloth_args)
        record.update(device_record(device))
        record.update(
            system="warp",
            integrator="symplectic",
            grid=dim,
            frames=args.frames,
            iterations=0,
            frame_seconds=times,
            median_frame_seconds=statistics.median(times),
            state=save_state(args.state_dir, f"warp_{dim}.f32", positions[-1]),
        )
        emit(record)


def newton_model(cloth, settings, solver, device):
    """Warp's benchmark cloth as a Newton model: the same particles, masses, pins and springs
    (no triangles, so no triangle forces or contacts), gravity along −y as in the benchmark."""
    import newton  # noqa: PLC0415
    import numpy as np  # noqa: PLC0415
    from newton.utils import color_graph  # noqa: PLC0415

    builder = newton.ModelBuilder(up_axis=newton.Axis.Y, gravity=(0.0, -9.81, 0.0))
    for p, w in zip(cloth.positions, cloth.inv_masses):
        builder.add_particle(tuple(float(c) for c in p), (0.0, 0.0, 0.0), 0.0 if w == 0.0 else 1.0 / float(w))
    pairs = cloth.spring_indices.reshape(-1, 2)
    for (i, j), ke, kd in zip(pairs, cloth.spring_stiffness, cloth.spring_damping):
        builder.add_spring(int(i), int(j), float(ke), float(kd), 0.0)
    if solver == "vbd":
        # builder.color() colours triangle and tet graphs only; this cloth has springs only, so
        # colour the spring graph with Newton's own colouring (no two ends of a spring share one).
        import warp as wp  # noqa: PLC0415

        edges = wp.array(np.sort(pairs, axis=1).astype(np.int32), dtype=int, device="cpu")
        builder.set_coloring(color_graph(builder.particle_count, edges))
    model = builder.finalize(device=device)
    # The like-for-like case: no particle-particle hash grid.
    model.particle_grid = None
    return model


def run_newton(args):
    import newton  # noqa: PLC0415
    import warp as wp  # noqa: PLC0415

    device = resolve_device(args.device)
    for dim in args.sizes:
        cloth, settings, cloth_args = warp_benchmark(dim)
        model = newton_model(cloth, settings, args.solver, device)
        if args.solver == "semi_implicit":
            solver = newton.solvers.SolverSemiImplicit(model, enable_tri_contact=False)
        else:
            solver = newton.solvers.SolverVBD(model, iterations=args.iterations, particle_enable_self_contact=False)
        control = model.control()
        frame_dt = 1.0 / settings["sim_fps"]
        sim_dt = frame_dt / args.substeps

        def advance(states, substeps):
            for _ in range(substeps):
                states[0].clear_forces()
                solver.step(states[0], states[1], control, None, sim_dt)
                states.reverse()

        # One untimed substep on a scratch state compiles Newton's kernels; the timed run
        # starts from rest.
        advance([model.state(), model.state()], 1)
        wp.synchronize()
        states = [model.state(), model.state()]
        # Newton's cloth examples replay a captured graph (a CUDA graph on the GPU; on the CPU
        # it saves Python's launch overhead too). A graph replays fixed buffers: with an even
        # substep count the ping-pong pair is back in place at the end of each frame.
        graph = None
        if args.substeps % 2 == 0:
            with wp.ScopedCapture(device=device) as capture:
                advance(states, args.substeps)
            graph = capture.graph

        def step():
            if graph is not None:
                wp.capture_launch(graph)
            else:
                advance(states, args.substeps)
            states[0].particle_q.numpy()

        times = time_frames(args.frames, step)
        record = describe_cloth(cloth, settings, cloth_args)
        record.update(device_record(device))
        record.update(
            system="newton",
            integrator="symplectic" if args.solver == "semi_implicit" else "implicit",
            solver=type(solver).__name__,
            grid=dim,
            frames=args.frames,
            substeps=args.substeps,
            iterations=args.iterations if args.solver == "vbd" else 0,
            frame_seconds=times,
            median_frame_seconds=statistics.median(times),
            state=save_state(args.state_dir, f"newton_{args.solver}_{dim}.f32", states[0].particle_q.numpy()),
        )
        emit(record)


def versions(_args):
    record = {"python": sys.version.split()[0]}
    for name in ("numpy", "warp", "newton"):
        try:
            module = __import__(name)
            record[name] = module.__version__
        except Exception as e:  # noqa: BLE001  (report what is missing, don't fail)
            record[name] = f"missing: {e}"
    emit(record)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("versions")
    for name in ("warp", "newton"):
        p = sub.add_parser(name)
        p.add_argument("--sizes", type=lambda s: [int(x) for x in s.split(",")], required=True)
        p.add_argument("--frames", type=int, required=True)
        p.add_argument("--state-dir", required=True)
        p.add_argument("--device", choices=["auto", "cpu", "cuda"], default="auto")
        if name == "newton":
            p.add_argument("--solver", choices=["semi_implicit", "vbd"], required=True)
            p.add_argument("--substeps", type=int, required=True)
            p.add_argument("--iterations", type=int, default=10)
    args = parser.parse_args()
    if args.command != "versions":
        # Warp's messages go to stderr; kernels compile into this environment's own cache
        # (benchmark_cloth_warp clears the cache it uses when imported).
        import warp as wp  # noqa: PLC0415

        wp.config.quiet = True
        wp.config.kernel_cache_dir = os.path.join(os.path.dirname(os.path.abspath(__file__)), f"{args.command}-kernels")
        wp.init()
    {"versions": versions, "warp": run_warp, "newton": run_newton}[args.command](args)


if __name__ == "__main__":
    main()
