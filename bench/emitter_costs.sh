#!/bin/sh
# The cost of each emitter per iteration: bench/emitter_costs.sh [SECONDS]
# The demo fog box (scenes/fogbox/fogbox.json, 128²) with its point light replaced by each kind of emitter
# at the same place (costs hardly depend on the flux): point, spot, an emissive quad, an emissive sphere (tessellated, 16,384
# triangles), a parallel collimated beam (radius 0.05), a diverging beam (radius 0.05, 2°) and a
# directional_point. Per emitter and method (plain path tracer, baseline photon points, DARTS photon points,
# DARTS path tracer), SECONDS each (default 10), one after the other on an otherwise idle machine: the
# milliseconds per pass (path tracer) or per iteration, and for photon points the photon pass's share. The
# table goes to bench/results/emitter-costs.md.
set -eu
secs=${1:-10}
bin=${DARTSPP:-build/dartspp}
[ -x "$bin" ] || make build/dartspp >&2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
out=bench/results/emitter-costs.md
python3 - "$work" <<'PY'
import json, sys
work = sys.argv[1]
base = json.load(open('scenes/fogbox/fogbox.json'))
base['camera']['resolution'] = [128, 128]
at = [0, 1.75, 0.1]
lights = {
    'point': {"type": "point", "emission": [6, 6, 6]},
    'spot': {"type": "spot", "emission": [30, 30, 30], "coneangle": 40, "conedeltaangle": 10,
             "transform": {"position": at, "look_at": [0, 0, 0.1], "up": [0, 0, 1]}},
    'quad': {"type": "quad", "bsdf": "white", "emission": [60, 60, 60], "int_medium": "fog",
             "transform": {"position": at, "scale": [0.2, 1, 0.2], "rotation": [180, 0, 0]}},
    'sphere': {"type": "sphere", "bsdf": "white", "emission": [19, 19, 19], "int_medium": "fog",
               "transform": {"position": at, "scale": 0.1}},
    'beam': {"type": "collimated", "radius": 0.05, "emission": [9600, 9600, 9600],
             "transform": {"position": at, "look_at": [0.3, 0, 0.3], "up": [0, 0, 1]}},
    'diverging-beam': {"type": "collimated", "radius": 0.05, "divergence": 2, "emission": [9600, 9600, 9600],
                       "transform": {"position": at, "look_at": [0.3, 0, 0.3], "up": [0, 0, 1]}},
    'directional-point': {"type": "directional_point", "power": [75, 75, 75],
                          "transform": {"position": at, "look_at": [0.3, 0, 0.3], "up": [0, 0, 1]}},
}
for name, L in lights.items():
    s = json.loads(json.dumps(base))
    prims = [p for p in s['primitives'] if p['type'] != 'point']
    L = dict(L, name=name, ext_medium="fog")
    L.setdefault("transform", {"position": at})
    s['primitives'] = prims + [L]
    json.dump(s, open(f'{work}/{name}.json', 'w'), indent=1)
PY
{
    echo "# The cost of each emitter per iteration"
    echo
    echo "bench/emitter_costs.sh $secs on $(date -u +%Y-%m-%d), $(nproc) cores ($(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')):"
    echo "the demo fog box at 128² with its light replaced by each emitter, $secs s per cell, one run at a time."
    echo "Path tracers: milliseconds per pass (one camera path per pixel). Photon points: milliseconds per"
    echo "iteration (100,000 light paths, 80,000 volume photons), in brackets the photon pass's share."
    echo
    echo "| emitter | path tracer ms/pass | DARTS PT ms/pass | baseline PP ms/iter | DARTS PP ms/iter |"
    echo "|---|---|---|---|---|"
} > "$out"
for name in point spot quad sphere beam diverging-beam directional-point; do
    row="| $name"
    for m in pt darts_pt pp darts_pp; do
        case $m in
            pt) set -- --set type=path_tracer --set enable_guiding=false --set enable_elliptical=false ;;
            darts_pt) set -- --set type=path_tracer ;;
            pp) set -- --set enable_guiding=false --set enable_elliptical=false ;;
            darts_pp) set -- ;;
        esac
        echo "emitter_costs: $name, $m" >&2
        "$bin" render "$work/$name.json" "$@" --time "$secs" --seed 1 --quiet --no-cube --no-viewer \
            --output "$work/$name-$m.exr" > "$work/$name-$m.txt" 2>/dev/null
        cell=$(awk '/^rendered/ { passes = $2; secs = $5 }
                    /time in photon pass/ { for (i = 4; i <= NF; i++) if ($i == "pass" && $(i-1) == "photon" && $(i-3) == "time") ph = $(i+1) }
                    END { if (passes > 0) { ms = 1000 * secs / passes
                          if (ph != "") printf "%.1f (%.0f %%)", ms, 100 * ph / secs; else printf "%.2f", ms } }' "$work/$name-$m.txt")
        row="$row | $cell"
    done
    echo "$row |" >> "$out"
done
cat "$out"
