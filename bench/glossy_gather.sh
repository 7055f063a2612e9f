#!/bin/sh
# Gather or continue at a glossy lobe: bench/glossy_gather.sh [SECONDS] [SEEDS] [REF_SECONDS]
# Photon points either gather surface photons with a glossy lobe evaluated or continue the camera path by
# sampling the lobe (surface_photon_split; the integrator key glossy_gather_alpha is the threshold α). For
# each roughness α in ALPHAS (default "0.02 0.05 0.1 0.2 0.4") of the rough_conductor back wall of
# bench/scenes/glossy/glossy.json (written from it with sed, one scene per α), this renders
#   - a path-tracer reference with bench/reference.sh (REF_SECONDS in all, default 240, as CHUNKS chunks,
#     default 4); its own noise V_ref, the variance of the mean of the chunks, is subtracted from every MSE;
#   - baseline photon points (guiding and elliptical control vertices off) with glossy_gather_alpha=0
#     ("gather": every glossy lobe is gathered, the reference renderer's rule) and glossy_gather_alpha=10
#     ("continue": every glossy lobe is continued), SECONDS each (default 20) at THREADS threads (default 2),
#     SEEDS seeds (default 3), the two arms alternating (gather first on odd seeds, continue first on even
#     ones), so a slow spell of the shared machine falls on both;
# and prints Markdown tables, also written to bench/results/glossy_gather.md (replaced): MSE − V_ref (mean
# over the seeds) of both arms and their ratio for the whole image, the highlight (the square HIGHLIGHT,
# default "45 48 65 68", around the mirror point of the light) and the rest of the metal wall (the rectangle
# METAL, default "30 28 96 84", without the highlight square); rectangles are x0 y0 x1 y1, top-down
# pixels, [x0,x1)×[y0,y1), like `dartspp patch-mean`. Then each arm's own variance over the seeds (no
# reference involved) and what is left, MSE − V_ref − variance ≈ bias² (mostly the gather's blur of a
# lobe over the gather disc), and the MSE of every seed.
# Images and logs go to OUT (default refs/glossy_gather, ignored by git). RENDER=0 only recomputes the
# tables from the images in OUT. The statistics need python3 (standard library only); dartspp is used
# through its command line only.
set -eu
secs=${1:-20}; seeds=${2:-3}; ref_secs=${3:-240}
alphas=${ALPHAS:-0.02 0.05 0.1 0.2 0.4}
threads=${THREADS:-2}
metal=${METAL:-30 28 96 84}
highlight=${HIGHLIGHT:-45 48 65 68}
out=${OUT:-refs/glossy_gather}
chunks=${CHUNKS:-4}
template=bench/scenes/glossy/glossy.json
table=bench/results/glossy_gather.md
command -v python3 >/dev/null || { echo "$0: python3 is needed for the statistics" >&2; exit 2; }
mkdir -p "$out"
if [ "${RENDER:-1}" != 0 ]; then
    if [ -z "${DARTSPP:-}" ]; then make build/dartspp >&2; fi # make: a binary older than src/ is rebuilt
    bin=${DARTSPP:-build/dartspp}
    started=$(date -u +%Y-%m-%dT%H:%MZ)
    for a in $alphas; do
        scene=$out/glossy-a$a.json
        sed "s/\"roughness\": [0-9.]*/\"roughness\": $a/" "$template" > "$scene"
        echo "α=$a: reference, $ref_secs s" >&2
        CHUNKS=$chunks DARTSPP=$bin bench/reference.sh "$scene" "$ref_secs" "$out/ref-a$a.pfm" > /dev/null
        s=1
        while [ "$s" -le "$seeds" ]; do
            if [ $((s % 2)) -eq 1 ]; then arms="gather continue"; else arms="continue gather"; fi
            for arm in $arms; do
                if [ "$arm" = gather ]; then g=0; else g=10; fi
                echo "α=$a: $arm, seed $s, $secs s" >&2
                "$bin" render "$scene" --set enable_guiding=false --set enable_elliptical=false \
                    --set glossy_gather_alpha=$g --threads "$threads" --time "$secs" --seed "$s" \
                    --quiet --output "$out/a$a-$arm-s$s.pfm" > "$out/a$a-$arm-s$s.txt"
            done
            s=$((s + 1))
        done
    done
    # the log of render runs into OUT, listed under the tables
    echo "- α = $alphas: rendered $started to $(date -u +%Y-%m-%dT%H:%MZ) by \`bench/glossy_gather.sh $secs $seeds $ref_secs\` (ALPHAS=\"$alphas\", THREADS=$threads, CHUNKS=$chunks)" >> "$out/runs.log"
fi

cat > "$out/stats.py" <<'EOF'
# stats.py OUT SEEDS "ALPHAS" "METAL" "HIGHLIGHT": the Markdown tables from the images in OUT
import array, glob, re, sys
out, seeds, alphas = sys.argv[1], int(sys.argv[2]), sys.argv[3].split()
metal, hl = [list(map(int, s.split())) for s in sys.argv[4:6]]

def read_pfm(p):
    with open(p, 'rb') as f:
        kind = f.readline().strip(); w, h = map(int, f.readline().split()); sc = float(f.readline())
        a = array.array('f'); a.frombytes(f.read())
    if kind != b'PF': sys.exit('not an RGB PFM: ' + p)
    if (sc > 0) != (sys.byteorder == 'big'): a.byteswap()
    return w, h, a

def inside(r, x, y): return r[0] <= x < r[2] and r[1] <= y < r[3]
def regions(w, h):  # channel-value indices of each region; PFM rows run bottom-up, rectangles top-down
    reg = {'whole': [], 'highlight': [], 'rest': []}
    for y in range(h):
        for x in range(w):
            i = 3 * ((h - 1 - y) * w + x)
            reg['whole'] += [i, i + 1, i + 2]
            if inside(hl, x, y): reg['highlight'] += [i, i + 1, i + 2]
            elif inside(metal, x, y): reg['rest'] += [i, i + 1, i + 2]
    return reg
def mse(a, b, idx): return sum((a[i] - b[i]) ** 2 for i in idx) / len(idx)
def var(ims, idx, of_mean=False):  # per-pixel sample variance over the images, averaged
    k = len(ims); s = 0.0
    for i in idx:
        v = [im[i] for im in ims]; m = sum(v) / k; s += sum((x - m) ** 2 for x in v) / (k - 1)
    return s / len(idx) / (k if of_mean else 1)
def passes(p):
    m = re.search(r'^rendered (\d+) passes', open(p).read(), re.M)
    return int(m.group(1)) if m else 0
def g(v): return '%.3g' % v
def ratio(a, b): return '%.2f' % (a / b) if b > 0 and a > 0 else '-'

R = ('whole', 'highlight', 'rest')
rows = {}
for a in alphas:
    ref = read_pfm('%s/ref-a%s.pfm' % (out, a)); w, h, r = ref
    reg = regions(w, h)
    ch = [read_pfm(p)[2] for p in sorted(glob.glob('%s/ref-a%s.chunk*.pfm' % (out, a)))]
    vref = {k: var(ch, reg[k], True) for k in R}
    row = {'vref': vref}
    for arm in ('gather', 'continue'):
        ims = [read_pfm('%s/a%s-%s-s%d.pfm' % (out, a, arm, s))[2] for s in range(1, seeds + 1)]
        per = [{k: mse(im, r, reg[k]) for k in R} for im in ims]
        m = {k: sum(p[k] for p in per) / seeds - vref[k] for k in R}
        v = {k: var(ims, reg[k]) for k in R} if seeds >= 2 else None
        it = [passes('%s/a%s-%s-s%d.txt' % (out, a, arm, s)) for s in range(1, seeds + 1)]
        row[arm] = {'mse': m, 'var': v, 'per': per, 'it': it}
    rows[a] = row

print('| α | passes per seed: gather / continue | whole: gather | continue | gather ÷ continue | highlight: gather | continue | gather ÷ continue | rest of the metal: gather | continue | gather ÷ continue | lower error (whole / highlight / rest) |')
print('|---|---|---|---|---|---|---|---|---|---|---|---|')
for a in alphas:
    G, C = rows[a]['gather'], rows[a]['continue']
    cells = []
    for k in R:
        cells += [g(G['mse'][k]), g(C['mse'][k]), '**%s**' % ratio(G['mse'][k], C['mse'][k])]
    win = ' / '.join('gather' if G['mse'][k] < C['mse'][k] else 'continue' for k in R)
    print('| %s | %s / %s | %s | %s |' % (a, ','.join(map(str, G['it'])), ','.join(map(str, C['it'])), ' | '.join(cells), win))
print()
print('Details: V_ref; each arm\'s variance of one run over the seeds (no reference); what is left, MSE − V_ref −')
print('variance ≈ bias² (it can come out negative by noise); the MSE against the reference of each seed. Triples are')
print('whole / highlight / rest of the metal.')
print()
print('| α | V_ref | variance, gather | variance, continue | left ≈ bias², gather | left ≈ bias², continue | MSE per seed (whole), gather | continue | MSE per seed (highlight), gather | continue |')
print('|---|---|---|---|---|---|---|---|---|---|')
for a in alphas:
    V, G, C = rows[a]['vref'], rows[a]['gather'], rows[a]['continue']
    tri = lambda d: ' / '.join(g(d[k]) for k in R) if d else '-'
    left = lambda A: ' / '.join(g(A['mse'][k] - A['var'][k]) for k in R) if A['var'] else '-'
    seedl = lambda A, k: ', '.join(g(p[k]) for p in A['per'])
    print('| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |' % (a, tri(V), tri(G['var']), tri(C['var']), left(G), left(C),
          seedl(G, 'whole'), seedl(C, 'whole'), seedl(G, 'highlight'), seedl(C, 'highlight')))
EOF

{
    echo "Gather or continue at a glossy lobe: \`bench/scenes/glossy/glossy.json\`, the back wall's roughness α set by sed;"
    echo "baseline photon points (\`enable_guiding=false enable_elliptical=false\`) with \`glossy_gather_alpha=0\` (gather every"
    echo "glossy lobe) and \`=10\` (continue through every glossy lobe), $secs s per run at \`--threads $threads\`, $seeds seeds,"
    echo "the arms alternating; path-tracer reference of $ref_secs s per α (\`bench/reference.sh\`, $chunks chunks)."
    echo "Every error is MSE − V_ref (per channel value, mean over the seeds; V_ref = the reference's own noise, from"
    echo "its chunks). Regions (top-down pixels, [x0,x1)×[y0,y1)): highlight \`$highlight\`, rest of the metal"
    echo "\`$metal\` without the highlight."
    echo "Machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'), shared with other jobs. Tables made"
    echo "$(date -u +%Y-%m-%dT%H:%MZ) by \`RENDER=${RENDER:-1} bench/glossy_gather.sh $secs $seeds $ref_secs\` (ALPHAS=\"$alphas\") from these renders:"
    echo
    cat "$out/runs.log" 2>/dev/null || echo "- (no log of the renders in $out)"
    echo
    python3 "$out/stats.py" "$out" "$seeds" "$alphas" "$metal" "$highlight"
} | tee "$table"
