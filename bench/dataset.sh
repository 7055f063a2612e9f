#!/bin/sh
# A small time-of-flight dataset from the gated-imaging demo (scenes/gated-fog): VIEWS camera positions along
# the road's width, each rendered as frames (the transient) through a SPAD-like time response, with ground
# truth, then counted as a photon-counting sensor would over PULSES laser pulses. The layout, the units and
# how to read it: README.md ("A time-of-flight dataset") and docs/sensor.md.
#   bench/dataset.sh [OUT_DIR] [SECONDS_PER_VIEW] [VIEWS]      (defaults: out/dataset 60 3)
# Environment: RES (default 128x80), PULSES (default 20000), THREADS (default 2).
set -eu
out=${1:-out/dataset}; secs=${2:-60}; views=${3:-3}
res=${RES:-128x80}; pulses=${PULSES:-20000}; threads=${THREADS:-2}
bin=${DARTSPP:-build/dartspp}
py=/usr/bin/python3 # Debian's, with NumPy (python3-numpy)
[ -x "$bin" ] || make build/dartspp >&2
"$py" -c "import numpy" 2>/dev/null || { echo "$0: needs NumPy for $py (apt-get install python3-numpy)" >&2; exit 2; }
mkdir -p "$out"
t0=$(date +%s)
v=0
while [ "$v" -lt "$views" ]; do
    d="$out/view_$v"
    mkdir -p "$d"
    # the scene with the camera (and the flash beside it) moved sideways by 0.5 m per view, from the left
    "$py" - "$v" "$views" scenes/gated-fog/gated-fog.json "$d/scene.json" "$res" <<'EOF'
import json, sys
v, n, src, dst, res = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3], sys.argv[4], sys.argv[5]
s = json.load(open(src))
dx = 0.5 * (v - (n - 1) / 2)
cam = s["camera"]["transform"]
cam["position"][0] += dx
cam["look_at"][0] += dx
for p in s["primitives"]:
    if p.get("type") == "spot":
        p["transform"]["position"][0] += dx
        if "look_at" in p["transform"]:
            p["transform"]["look_at"][0] += dx
w, h = (int(x) for x in res.split("x"))
s["camera"]["resolution"] = [w, h]
i = s["integrator"]
for k in ("transient_time_center",):
    i.pop(k, None)
i.update({"start_time": 40.0, "transient_time_width": 1.0, "frame_num": 30,    # 30 frames of 1 m: [40, 70)
          "sensor_jitter_fwhm": 0.3, "sensor_jitter_tail": 0.45,                # 1 ns FWHM, 1.5 ns tail
          "bounce_orders": 2})                                                   # direct, single, multiple
s["renderer"].update({"ground_truth": True, "timeout": 0, "spp": 0})
json.dump(s, open(dst, "w"), indent=1)
EOF
    "$bin" render "$d/scene.json" --time "$secs" --threads "$threads" --seed $((v + 1)) --output "$d/render.exr" \
        --no-viewer --quiet --overwrite > "$d/render.log" 2>&1 || { tail -5 "$d/render.log" >&2; exit 1; }
    # photons per unit of pixel value and time: the brightest frames' 99th percentile pixel expects 0.05
    # detections per pulse (low flux, little pile-up)
    scale=$("$py" -c "import numpy as np, sys; c = np.load(sys.argv[1]).mean(-1); q = np.quantile(c, 0.99); print(0.05 / q if q > 0 else 1.0)" "$d/render_cube.npy")
    "$bin" counts "$d/render_cube.npy" --output "$d/counts.npy" --pulses "$pulses" --scale "$scale" \
        --efficiency 0.3 --dark-rate 1e-4 --ambient-rate 2e-3 --dead-time 100 --coates --seed $((v + 1)) \
        > "$d/counts.log" 2>&1 || { tail -5 "$d/counts.log" >&2; exit 1; }
    echo "view $v: $(grep '^rendered' "$d/render.log"); $(grep 'counts (' "$d/counts.log" | sed 's/^dartspp counts: //')"
    v=$((v + 1))
done
"$py" - "$out" "$views" <<'EOF'
import json, os, sys
out, n = sys.argv[1], int(sys.argv[2])
files = {
    "scene.json": "the scene rendered (the demo with the camera and flash moved, frames, sensor response, ground truth)",
    "render.exr": "the image of the union window [40, 70) m, float32 RGB",
    "render_cube.npy": "the transient: float32 (30, H, W, 3), radiance averaged over each 1 m frame, through the sensor's response",
    "render_frames.csv": "each frame's [start, end) in metres of light path",
    "render_NNNN.exr": "the same frames as EXR images",
    "render_orders.npy": "float32 (3, 30, H, W, 3): the frames of the paths of 0, 1, and 2 or more scattering events (they sum to the cube)",
    "render_depth.exr": "metres from the camera to the first surface per pixel (0: none)",
    "render_arrival.exr": "metres of light path of the first return through that surface (flash to surface to camera; 0: none)",
    "render_normal.exr": "the surface's normal in world coordinates, facing the camera",
    "render_albedo.exr": "the surface's albedo",
    "counts.npy": "int32 (30, H, W): photon counts per frame over the pulses (SPAD, one detection per pulse)",
    "counts.json": "the counting parameters, the model and the time axis",
    "counts_coates.npy": "float32 (30, H, W): the transient estimated back from the counts (Coates), the cube's unit",
}
json.dump({"views": [f"view_{v}" for v in range(n)], "files": files, "time_unit": "metres of light path (1 m = 3.336 ns)"},
          open(os.path.join(out, "index.json"), "w"), indent=1)
EOF
echo "dataset: $views views in $out ($(($(date +%s) - t0)) s); index: $out/index.json"
