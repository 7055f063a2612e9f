#!/usr/bin/env bash
# Pixel data of two dartspp binaries side by side: the path tracer, baseline photon points, DARTS, DARTS with
# EDA and DARTS frame mode, on the demo and on the fog Cornell box, and DARTS on the paper's dragon at 64² with
# surface chains on (when the paper's scenes are beside the checkout), at a fixed seed and pass count. Prints one
# line per case, "identical" or "DIFFER", and exits 1 if any differs. A refactor that must not change
# behaviour is checked this way against the binary built from the commit before it:
#   git worktree add /tmp/base <commit> && make -C /tmp/base build/dartspp
#   bench/same_images.sh /tmp/base/build/dartspp build/dartspp
set -u
old=${1:?usage: same_images.sh OLD_DARTSPP NEW_DARTSPP}; new=${2:?usage: same_images.sh OLD_DARTSPP NEW_DARTSPP}
here=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
common="--spp 3 --seed 11 --threads 2 --quiet --set resolution=48"
baseline="--set enable_guiding=false --set enable_elliptical=false --set strict_time_width=false"
eda="--set eda=true --set eda_shape=[16,16,32] --set eda_table_dir=$work/tables"
paper=${DARTSPP_PAPER_SCENES:-$here/../shared/scenes}
bad=0
while IFS='|' read -r name scene args; do
  [ -n "$name" ] || continue
  case $scene in
    paper:*) scene=$paper/${scene#paper:}
             [ -f "$scene" ] || { echo "$name: skipped ($scene not found)"; continue; } ;;
    *) scene=$here/$scene ;;
  esac
  for which in old new; do
    bin=${!which}
    # shellcheck disable=SC2086
    "$bin" render "$scene" $common $args --output "$work/$which/$name.pfm" >/dev/null 2>"$work/$which-$name.err" ||
      { echo "$name: $which binary failed: $(tail -1 "$work/$which-$name.err")"; bad=1; continue 2; }
  done
  same=1
  for f in "$work/old/$name".pfm "$work/old/$name"_*.pfm; do
    [ -e "$f" ] || continue
    cmp -s "$f" "$work/new/${f#"$work/old/"}" || same=0
  done
  if [ $same = 1 ]; then echo "$name: identical"; else echo "$name: DIFFER"; bad=1; fi
done <<CASES
demo-path-tracer|scenes/fogbox/fogbox.json|--set type=path_tracer --set enable_guiding=false --set enable_elliptical=false
demo-baseline|scenes/fogbox/fogbox.json|$baseline
demo-darts|scenes/fogbox/fogbox.json|
demo-darts-eda|scenes/fogbox/fogbox.json|$eda
demo-darts-frames|scenes/fogbox/fogbox.json|--set frame_num=4 --set transient_time_width=0.5 --set start_time=5
cbox-path-tracer|scenes/cbox-fog/path_tracer.json|
cbox-baseline|scenes/cbox-fog/transient.json|$baseline
cbox-darts|scenes/cbox-fog/transient.json|
cbox-darts-eda|scenes/cbox-fog/transient.json|$eda
cbox-darts-frames|scenes/cbox-fog/transient.json|--set frame_num=4 --set transient_time_width=0.2 --set start_time=15.8
dragon-darts-chains|paper:dragon/scene-points-darts-short.json|--set resolution=64 --set surface_chains=true
CASES
exit $bad
