#!/usr/bin/env bash
# Volume photon map benchmark: the kd-tree of src/photon/volume_map.c against Embree 3 (user geometry, and
# disc points with a filter), on photons spread like the fog Cornell box and its 512x512 camera rays.
# Builds bench/map_bench.c, runs it (about 3 minutes on 2 cores) and writes bench/results/volume_map.md.
#   bench/map_bench.sh            # from the repository root or anywhere
set -euo pipefail
cd "$(dirname "$0")/.."

out=bench/results/volume_map.md
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
bin=$work/map_bench
cc=${CC:-gcc}
cflags="-std=c11 -D_GNU_SOURCE -O2 -fopenmp -Iinclude"
sources="bench/map_bench.c src/photon/volume_map.c src/core/error.c src/core/rng.c src/core/sampling.c"
# N:SIDE — 4e4 is the fog Cornell box's volume_photon_count; 1e7 runs a 64x64 subsample of the rays
sizes="40000:512 100000:512 1000000:512 10000000:64"

# shellcheck disable=SC2086
$cc $cflags $sources -lembree3 -lm -o "$bin"

cpu=$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//')
load_before=$(cut -d' ' -f1-3 /proc/loadavg)
start=$(date +%s)
"$bin" $sizes >"$work/table.md"
seconds=$(( $(date +%s) - start ))
load_after=$(cut -d' ' -f1-3 /proc/loadavg)

mkdir -p "$(dirname "$out")"
{
  echo "# Volume photon map: kd-tree vs Embree 3"
  echo
  echo "- date: $(date -I)"
  echo "- machine: $(nproc) cores, ${cpu}, $(awk '/MemTotal/ {printf "%.0f GB", $2 / 1048576}' /proc/meminfo) RAM"
  echo "- command: \`bench/map_bench.sh\`, which compiles \`$cc $cflags $sources -lembree3 -lm -o map_bench\`"
  echo "  and runs \`map_bench ${sizes}\`"
  echo "- run time ${seconds} s; load average (1, 5, 15 min) before: ${load_before}, after: ${load_after}"
  echo
  echo "Workload: N photons in the box [0, 5.56] x [0, 5.49] x [0, 5.59], half uniform and half at an exponential"
  echo "distance (mean 1) from the light at (2.78, 4.8, 2.4); gather radius 0.1. Rays: pinhole at (2.78, 2.73, -8)"
  echo "looking +z, 39.31 degrees horizontal field of view, through the pixel centres of a SIDE x SIDE grid"
  echo "covering the 512 x 512 image (SIDE = 512: every pixel; the 10^7 row uses a 64 x 64 subsample); each"
  echo "segment runs from the camera to where the ray leaves the box. The visit callback adds up the 2-D"
  echo "biweight kernel times the photon power (the gather without phase function and time gate)."
  echo
  cat "$work/table.md"
  echo
  echo "Columns: build = best of 2 builds, wall time, including copying the photons (kd-tree) or filling the"
  echo "Embree buffers; Embree devices are created with \`threads=1\` / \`threads=2\` beforehand and not timed."
  echo "Query = wall time over all rays divided by their number (OpenMP, dynamic schedule). \"Same photons\""
  echo "compares the total number of photons found over all rays. The last column estimates one renderer"
  echo "iteration: one build plus 512² camera rays, both with 2 threads."
  echo
  echo "Embree variants (both in bench/map_bench.c; Embree's float traversal only proposes candidates, and the"
  echo "map's exact double-precision test decides, so the photons found are the kd-tree's): *user geometry* —"
  echo "one primitive per photon with bounds photon ± r (grown by 1e-4 relative), whose intersect callback tests"
  echo "and records the photon and never reports a hit, so the ray keeps its tfar and traversal reaches every"
  echo "candidate; *disc points* — ray-facing discs of radius r (1 + 1e-4) with an intersection filter that"
  echo "records the photon and rejects the hit. Both use \`RTC_BUILD_QUALITY_LOW\` (maps are rebuilt every"
  echo "iteration; MEDIUM built slower and queried no faster in trial runs) and \`RTC_SCENE_FLAG_ROBUST\`."
  echo
  echo "kd-tree leaf size (LEAF_MAX in src/photon/volume_map.c), from trial runs of this workload, single-thread"
  echo "query µs/ray for 10⁴ / 4·10⁴ / 10⁵ / 10⁶ photons: 4 → 0.64 / 1.70 / 3.80 / 23.9; 8 → 0.57 / 1.43 / 3.01 / 19.4;"
  echo "**16 → 0.56 / 1.34 / 2.72 / 17.2**; 32 → 0.64 / 1.41 / 2.73 / 15.9. The renderer's scenes use 4·10⁴ to"
  echo "2·10⁵ volume photons per iteration, where 16 is best."
  echo
  case "$(grep '^Faster:' "$work/table.md")" in
    *"kd-tree at every size"*)
      echo "**The renderer keeps the kd-tree** (\`src/photon/volume_map.c\`, behind \`photon_map_query_beam\`): it gave"
      echo "the cheaper iteration at every size measured here, and it visits photons in a deterministic order." ;;
    *"depends on the size"*)
      echo "**The renderer keeps the kd-tree** (\`src/photon/volume_map.c\`, behind \`photon_map_query_beam\`): Embree"
      echo "came out ahead only at the sizes named in the line above, the kd-tree everywhere else; the kd-tree also"
      echo "visits photons in a deterministic order." ;;
    *)
      echo "**Embree was faster in this run.** The renderer still calls the kd-tree (\`src/photon/volume_map.c\`,"
      echo "behind \`photon_map_query_beam\`); switching would mean moving the Embree variant behind that API." ;;
  esac
} >"$out"
echo "wrote $out (${seconds} s)"
