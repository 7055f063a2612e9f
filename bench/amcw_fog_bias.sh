#!/bin/bash
# The multipath bias that fog adds to AMCW depth (docs/amcw.md §5): a white Lambertian wall at distance D across
# the axis of a pinhole camera (fov 10°, 32 × 32), lit by a spot light beside the camera (0.1 m to its side,
# aimed parallel to its axis, half-angle 8°: the camera's illuminator; coaxial, the single scattering right in
# front of the lens would grow without bound as 1/distance²), the space between them a box of homogeneous fog (8 m wide and high, from 0.5 m behind the
# camera to 0.5 m behind the wall; Henyey–Greenstein g, σa 0) of scattering coefficient σs per metre; the path
# tracer (steady state, amcw_frequencies [20, 25] MHz). Per σs: the mean AMCW depth of the central 8 × 8 pixels,
# unwrapped and from each frequency alone, and its bias against the clear-air render (σs 0: the geometric depth
# t/2 of those pixels), as the mean ± standard error over SEEDS renders of different seeds.
#   bench/amcw_fog_bias.sh [SPP] [D] [G] [SEEDS]   (defaults 256, 5, 0.8, 4; writes under out/amcw_fog_bias/)
set -euo pipefail
cd "$(dirname "$0")/.."
SPP=${1:-256}
D=${2:-5}
G=${3:-0.8}
SEEDS=${4:-4}
OUT=out/amcw_fog_bias
mkdir -p "$OUT"
make -s build/dartspp
PY=/usr/bin/python3
for S in 0 0.01 0.02 0.05 0.1 0.2; do
  cat > "$OUT/scene_$S.json" <<JSON
{ "media": [ { "name": "fog", "type": "homogeneous", "sigma_s": $S, "sigma_a": 0,
    "phase_function": { "type": "henyey_greenstein", "g": $G } } ],
  "bsdfs": [ { "name": "white", "type": "lambert", "albedo": 0.8 } ],
  "primitives": [
    { "type": "quad", "bsdf": "white", "transform": { "position": [0, 0, $D], "scale": [40, 1, 40], "rotation": [-90, 0, 0] } },
    { "type": "cube", "bsdf": { "type": "forward" }, "int_medium": "fog",
      "transform": { "position": [0, 0, $(echo "$D / 2" | bc -l)], "scale": [8, 8, $(echo "$D + 1" | bc -l)] } },
    { "type": "spot", "emission": [100, 100, 100], "coneangle": 8, "conedeltaangle": 1, "ext_medium": "fog",
      "transform": { "position": [0.1, 0, 0], "look_at": [0.1, 0, 1], "up": [0, 1, 0] } } ],
  "camera": { "type": "pinhole", "resolution": [32, 32], "fov": 10, "medium": "fog",
    "transform": { "position": [0, 0, 0], "look_at": [0, 0, 1], "up": [0, 1, 0] } },
  "integrator": { "type": "path_tracer", "max_bounces": 32 },
  "renderer": { "spp": $SPP, "amcw_frequencies": [20, 25] } }
JSON
  for K in $(seq 1 "$SEEDS"); do
    ./build/dartspp render "$OUT/scene_$S.json" --quiet --seed "$K" --output "$OUT/s_${S}_$K.exr" >/dev/null
  done
done
$PY - "$OUT" "$D" "$G" "$SPP" "$SEEDS" <<'PY'
import sys, numpy as np
out, D, G, spp, seeds = sys.argv[1], float(sys.argv[2]), sys.argv[3], sys.argv[4], int(sys.argv[5])
c0 = 299792458.0
sig = ["0", "0.01", "0.02", "0.05", "0.1", "0.2"]
print("wall at %g m, HG g %s, %s passes x %d seeds, 20 and 25 MHz; central 8x8 pixels; mean +- standard error over the seeds" % (D, G, spp, seeds))
print("| σs (1/m) | optical depth to the wall and back | AMCW depth, unwrapped (m) | its bias (mm) | 20 MHz alone: bias (mm) | 25 MHz alone: bias (mm) |")
print("|---|---|---|---|---|---|")
c = slice(12, 20)
def depths(s, k):
    a = np.load("%s/s_%s_%d_amcw.npy" % (out, s, k))
    d = np.load("%s/s_%s_%d_amcw_depth.npy" % (out, s, k))
    r = [float(d[c, c].mean())]
    for j, f in enumerate((20e6, 25e6)):
        phi = np.mod(-np.angle(a[j][c, c].mean(axis=-1)), 2 * np.pi)
        r.append(float((phi * c0 / (4 * np.pi * f)).mean()))
    return np.array(r)
ref = np.mean([depths("0", k) for k in range(1, seeds + 1)], axis=0)
for s in sig:
    v = np.array([depths(s, k) for k in range(1, seeds + 1)])
    m, se = v.mean(axis=0), v.std(axis=0, ddof=1) / np.sqrt(seeds) if seeds > 1 else np.zeros(3)
    b = 1e3 * (m - ref)
    print("| %s | %.2f | %.4f | %+.1f ± %.1f | %+.1f ± %.1f | %+.1f ± %.1f |" % (s, 2 * D * float(s), m[0], b[0], 1e3 * se[0],
          b[1], 1e3 * se[1], b[2], 1e3 * se[2]))
PY
