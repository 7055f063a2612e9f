#!/bin/sh
# The DARTS authors' collimated slab scenes (../shared/scenes/collimated, or $DARTSPP_PAPER_SCENES): our path
# tracer and baseline photon points on the transmitted pulse. bench/collimated_slabs.sh [SECONDS] [SEEDS]
# Renders transient-3cm.json and transient-5cm.json unchanged (photon points, the files' integrator) and with
# `--set type=path_tracer`, SECONDS each (default 60), SEEDS seeds (default 3), and prints per scene and
# method the curve of the central 16 × 16 pixels over the 500 frames: its total, mean time and width (the
# standard deviation of time), mean ± standard error over the seeds. Table: bench/results/collimated-slabs.md.
set -eu
secs=${1:-60}; seeds=${2:-3}
bin=${DARTSPP:-build/dartspp}
[ -x "$bin" ] || make build/dartspp >&2
dir=${DARTSPP_PAPER_SCENES:-../shared/scenes}/collimated
[ -f "$dir/transient-3cm.json" ] || { echo "$0: no $dir/transient-3cm.json" >&2; exit 2; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
out=bench/results/collimated-slabs.md
{
    echo "# The collimated slab scenes: path tracer against photon points"
    echo
    echo "bench/collimated_slabs.sh $secs $seeds on $(date -u +%Y-%m-%d), $(nproc) cores: each file unchanged (baseline photon"
    echo "points, its own integrator keys) and with type=path_tracer, $secs s per render, $seeds seeds. The curve of the"
    echo "central 16 × 16 pixels over the 500 frames: mean ± standard error over the seeds."
    echo
    echo "| slab | method | passes | total | mean time | width (sd of time) |"
    echo "|---|---|---|---|---|---|"
} > "$out"
for cm in 3 5; do
    for m in pp pt; do
        s=1
        while [ "$s" -le "$seeds" ]; do
            set --
            [ "$m" = pt ] && set -- --set type=path_tracer
            echo "collimated_slabs: ${cm} cm, $m, seed $s" >&2
            "$bin" render "$dir/transient-${cm}cm.json" "$@" --time "$secs" --seed "$s" --quiet --no-viewer \
                --output "$work/$cm-$m-$s.exr" > "$work/$cm-$m-$s.txt" 2>/dev/null
            rm -f "$work/$cm-$m-$s"_0*.exr
            s=$((s + 1))
        done
        python3 - "$work" "$cm" "$m" "$seeds" >> "$out" <<'PY'
import ast, struct, sys, re
work, cm, m, seeds = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
def cube(path):
    with open(path, 'rb') as f:
        f.read(8)
        n = struct.unpack('<H', f.read(2))[0]
        shape = ast.literal_eval(f.read(n).decode())['shape']
        return shape, f.read()
rows, passes = [], []
for s in range(1, seeds + 1):
    (F, H, W, C), raw = cube(f'{work}/{cm}-{m}-{s}_cube.npy')
    txt = open(f'{work}/{cm}-{m}-{s}.txt').read()
    passes.append(int(re.search(r'rendered (\d+) passes', txt).group(1)))
    start, width = {'3': (0.03, 1e-4), '5': (0.05, 1e-3)}[cm]
    m0 = m1 = m2 = 0.0
    for k in range(F):
        v = 0.0
        for y in range(H // 4, 3 * H // 4):
            off = ((k * H + y) * W + W // 4) * C
            v += sum(struct.unpack_from('<%df' % (W // 2 * C), raw, 4 * off))
        t = start + (k + 0.5) * width
        m0 += v; m1 += v * t; m2 += v * t * t
    mean = m1 / m0
    rows.append((m0 / (H * W // 4 * C), mean, (m2 / m0 - mean * mean) ** 0.5))
def ms(xs):
    n = len(xs); mu = sum(xs) / n
    se = (sum((x - mu) ** 2 for x in xs) / (n - 1) / n) ** 0.5 if n > 1 else float('nan')
    return mu, se
tot, mt, wd = (ms([r[i] for r in rows]) for i in range(3))
name = {'pp': 'baseline photon points', 'pt': 'path tracer'}[m]
print(f'| {cm} cm | {name} | {sum(passes) / len(passes):.0f} | {tot[0]:.4g} ± {tot[1]:.2g} | {mt[0]:.5f} ± {mt[1]:.1e} | {wd[0]:.5f} ± {wd[1]:.1e} |')
PY
    done
done
cat "$out"
