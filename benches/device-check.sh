#!/usr/bin/env bash
# Checks and times this machine's GPU and CPU with a built drapekit binary; builds nothing.
#
#   benches/device-check.sh [--quick] [--drapekit BIN] [--out DIR]
#
# BIN: the drapekit binary (default $DRAPEKIT, else target/release/drapekit).
# DIR: the results folder (default device-check-<date>); it must not exist yet.
# --quick: tiny sizes and a short scene (seconds; what CI runs on a software adapter).
#
# Run it from the repository root (it reads fixtures/). Every step runs under `timeout`; a
# failed step is recorded in steps.tsv and the script goes on. The exit status is 0 when every
# step passed, 1 when one failed, 2 for bad arguments. summary.md gathers every figure with the
# command that made it. Needs bash, coreutils and python3 (standard library only).
set -uo pipefail

quick=0
bin="${DRAPEKIT:-target/release/drapekit}"
out="device-check-$(date +%Y%m%d-%H%M%S)"
usage() { sed -n '4,8p' "$0" | sed 's/^# \{0,1\}//' >&2; }
while [ $# -gt 0 ]; do
    case "$1" in
        --quick) quick=1 ;;
        --drapekit) bin="${2:?--drapekit needs a path}"; shift ;;
        --out) out="${2:?--out needs a folder}"; shift ;;
        -h | --help) usage; exit 0 ;;
        *) echo "device-check: unknown argument $1" >&2; usage; exit 2 ;;
    esac
    shift
done
if [ ! -x "$bin" ]; then
    echo "device-check: no drapekit binary at $bin (build one with cargo build --release," \
        "or pass --drapekit BIN or set DRAPEKIT)" >&2
    exit 2
fi
if [ ! -d fixtures/scenes ]; then
    echo "device-check: run it from the repository root (no fixtures/scenes here)" >&2
    exit 2
fi
if [ -e "$out" ]; then
    echo "device-check: $out exists; pass a new folder with --out" >&2
    exit 2
fi
bin="$(cd "$(dirname "$bin")" && pwd)/$(basename "$bin")"
mkdir -p "$out/logs" || exit 2
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
cores="$(nproc)"

# Sizes and limits of the full run, and of --quick.
if [ "$quick" = 1 ]; then
    sizes=8,16
    peer_sizes=8,16
    implicit_sizes=8
    scaling_sizes=8
    peer_frames=2
    scaling_frames=2
    shirt_frames=(--frames 2)
    bench_args=(--substeps 5 --repeats 1)
    profile_args=(--substeps 2)
    profile_frames=1
    long=120
else
    sizes=128,256,512,1024
    peer_sizes=128,256,512,1024
    implicit_sizes=128,256
    scaling_sizes=128,256
    peer_frames=30
    scaling_frames=10
    shirt_frames=()
    bench_args=()
    profile_args=()
    profile_frames=5
    long=300
    # The 5 mm shirt's coarse start must settle before its frames count, so it runs whole
    # (about a minute on a recent GPU) and is stopped like Ctrl-C after this many seconds.
    hires_limit=120
fi

steps="$out/steps.tsv"
printf 'step\tstatus\tseconds\tcommand\n' >"$steps"
failed=0

# step NAME TIMEOUT_S COMMAND...: runs COMMAND under timeout, its output in logs/NAME.log, and
# records its status and wall time.
step() {
    local name="$1" limit="$2"
    shift 2
    local start end status label
    echo "== $name: $*" >&2
    start="$(date +%s%N)"
    # SIGINT as Ctrl-C: a run stopped by the limit writes its checkpoint and says its frame.
    timeout --signal=INT --kill-after=15 "$limit" "$@" >"$out/logs/$name.log" 2>&1
    status=$?
    end="$(date +%s%N)"
    if [ "$status" = 0 ]; then
        label=ok
    elif [ "$status" = 124 ] || [ "$status" = 137 ]; then
        label="timeout after ${limit} s"
        failed=1
    else
        label="failed (exit $status)"
        failed=1
    fi
    echo "   $label" >&2
    # The command as typed, with the binary's path shortened to `drapekit`.
    local cmd="$*"
    cmd="${cmd//$bin/drapekit}"
    local ms=$(((end - start) / 1000000))
    printf '%s\t%s\t%d.%03d\t%s\n' "$name" "$label" $((ms / 1000)) $((ms % 1000)) "$cmd" >>"$steps"
}

# The machine.
{
    echo "## drapekit info"
    "$bin" info 2>&1
    echo
    echo "## drapekit --version"
    "$bin" --version 2>&1
    if command -v nvidia-smi >/dev/null; then
        echo
        echo "## nvidia-smi"
        nvidia-smi 2>&1
        echo
        echo "## nvidia-smi --query-gpu"
        nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv 2>&1
    fi
    if command -v lscpu >/dev/null; then
        echo
        echo "## lscpu"
        lscpu 2>&1
    fi
    echo
    echo "## nproc"
    echo "$cores"
    echo
    echo "## uname -a"
    uname -a
} >"$out/machine.txt"
step info 60 "$bin" info

# The shirts: the cotton T-shirt on the GPU and the CPU, the 5 mm shirt on the GPU.
cotton=fixtures/scenes/tshirt_drape_cotton.toml
hires=fixtures/scenes/tshirt_drape_hires.toml
step shirt_cotton_gpu "$long" "$bin" run "$cotton" --backend gpu --quiet "${shirt_frames[@]}" \
    --out "$out/shirt_cotton_gpu"
step shirt_cotton_cpu "$long" "$bin" run "$cotton" --backend cpu --quiet "${shirt_frames[@]}" \
    --out "$out/shirt_cotton_cpu"
if [ "$quick" = 1 ]; then
    printf 'shirt_hires_gpu\tskipped (--quick)\t0\t-\n' >>"$steps"
else
    step shirt_hires_gpu "$hires_limit" "$bin" run "$hires" --backend gpu --quiet \
        --out "$out/shirt_hires_gpu"
fi

# Whole substeps at each grid size, once per GPU memory layout (unset: drapekit's choice).
step bench "$long" "$bin" bench --sizes "$sizes" "${bench_args[@]}" --out "$out/bench"
for layout in textures buffers; do
    step "bench_layout_$layout" "$long" env DRAPEKIT_GPU_LAYOUT="$layout" \
        "$bin" bench --sizes "$sizes" "${bench_args[@]}" --out "$out/bench_layout_$layout"
done

# Where the GPU's time goes: each stage at each size, and the cotton T-shirt's implicit solve.
step profile "$long" "$bin" bench profile --sizes "$sizes" "${profile_args[@]}" --scene "$cotton" \
    --frames "$profile_frames" --out "$out/profile"

# drapekit on Warp's benchmark cloth, both integrators (the implicit one at the smaller sizes).
step peer "$long" "$bin" bench peer --systems drapekit --sizes "$peer_sizes" \
    --newton-sizes "$implicit_sizes" --frames "$peer_frames" --out "$out/peer"

# Thread scaling of the CPU's implicit path, up to this machine's cores.
for threads in 1 2 4 8 16; do
    [ "$threads" -le "$cores" ] || break
    step "threads_$threads" "$long" "$bin" --threads "$threads" bench peer --systems drapekit \
        --sizes "${scaling_sizes%%,*}" --newton-sizes "$scaling_sizes" --frames "$scaling_frames" \
        --out "$out/threads_$threads"
done

# Warp and Newton beside drapekit, where this Python has them (PYTHONPATH may carry them).
if python3 -c "import warp, newton" >/dev/null 2>&1; then
    step peers "$long" "$bin" bench peer --systems drapekit,warp,newton --sizes "$peer_sizes" \
        --newton-sizes "$implicit_sizes" --frames "$peer_frames" --python "$(command -v python3)" \
        --no-venv --venv "$out/peer-driver" --out "$out/peers"
else
    printf 'peers\tskipped (python3 cannot import warp and newton)\t0\t-\n' >>"$steps"
fi

if ! python3 "$(dirname "$0")/device_check_summary.py" "$out" "$quick" 2>"$out/logs/summary.log"; then
    echo "device-check: summary.md failed, see $out/logs/summary.log" >&2
    failed=1
fi
echo "device-check: results in $out (summary.md)" >&2
exit "$failed"
