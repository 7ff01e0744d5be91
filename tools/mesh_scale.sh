#!/usr/bin/env bash
# Meshes at scale (issue 39): large closed bodies of water, like the final scene's, loaded,
# built and rendered by the renderer, with the peak resident memory per triangle; then, when
# Embree 3 is installed, the BVH build against Embree's on the harness's wave mesh of the same
# size, in alternating rounds (one engine at a time, the order swapped each round).
#
#   bash tools/mesh_scale.sh                       # n = 4097 (33.6M triangles) and 5001 (50.1M)
#   SIZES="1001 2049" ROUNDS=3 bash tools/mesh_scale.sh
#
# Environment (defaults in brackets):
#   SIZES     grid sides of the water surfaces and of the wave meshes   [4097 5001]
#   ROUNDS    alternating build rounds per size; 0 skips Embree         [2]
#   DATA_DIR  where the meshes, scene, images and logs go               [/tmp/caustic_mesh_scale]
#   BENCH     the Embree harness's folder                      [../shared/bench beside the checkout]
# Needs about 1 GB of disk per 17M triangles, GNU time (/usr/bin/time) and, for the build
# rounds, libembree-dev and gcc. The renders are 512x512 with photon mapping (the box's lamp
# and a refractive water body: caustic and global maps, the irradiance cache).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
sizes="${SIZES:-4097 5001}"
rounds="${ROUNDS:-2}"
data="${DATA_DIR:-/tmp/caustic_mesh_scale}"
bench="${BENCH:-$here/../shared/bench}"
case "$sizes$rounds" in *[!0-9\ ]*) echo "SIZES and ROUNDS are whole numbers" >&2; exit 2 ;; esac
for n in $sizes; do
  if ((n < 2 || n > 8193)); then echo "each of SIZES must be 2 to 8193" >&2; exit 2; fi
done
((rounds <= 20)) || { echo "ROUNDS must be at most 20" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "GNU time is missing: apt-get install -y time" >&2; exit 1; }

cd "$here"
cargo build --release --quiet --bin caustic
cargo build --release --quiet -p caustic-tools --bin water --bin bench_traversal
mkdir -p "$data"
cat >"$data/box.lua" <<'EOF'
-- A large mesh (-D MESH=file) in a white box under an area light: mesh_scale.sh's scene.
white = gr.material({0.7, 0.7, 0.7}, {0, 0, 0}, 0)
water = gr.material({0, 0, 0}, {0, 0, 0}, 0, 1, 1.33, 0)
root = gr.node('root')
local function wall(name, sx, sy, sz, tx, ty, tz)
  local w = gr.cube(name); w:set_material(white); w:scale(sx, sy, sz); w:translate(tx, ty, tz)
  root:add_child(w)
end
wall('floor', 2.2, 0.1, 2.2, -1.1, -1.1, -1.1)
wall('ceiling', 2.2, 0.1, 2.2, -1.1, 1.0, -1.1)
wall('back', 2.2, 2.2, 0.1, -1.1, -1.1, -1.1)
wall('left', 0.1, 2.2, 2.2, -1.1, -1.1, -1.1)
wall('right', 0.1, 2.2, 2.2, 1.0, -1.1, -1.1)
-- -D COPIES=k places the mesh k times side by side, each scaled to 1/k of the width.
m = gr.mesh('water', MESH); m:set_material(water)
local k = COPIES or 1
for i = 1, k do
  local copy = gr.node('copy ' .. i); copy:add_child(m)
  copy:scale(1 / k, 1, 1); copy:translate(-1.05 + (i - 0.5) * 2.1 / k, -0.2, 0)
  root:add_child(copy)
end
lamp = gr.area_light({0, 0.99, 0}, {3.5, 3.5, 3.5}, {0, 0, 1}, 1, nil, {0.3, 0, 0}, {0, 0, 0.3})
gr.render(root, 'box.png', 512, 512, {0, 0, 3.6}, {0, 0, -1}, {0, 1, 0}, 40, {0, 0, 0}, {lamp})
EOF

echo "| mesh | file | scene build (load + BVH) | BVH nodes, leaves, order | peak resident | per triangle stored | render, wall |"
echo "|---|---|---|---|---|---|---|"
# One row per render: SIZE and COPIES.
row() {
  local n="$1" copies="$2" glb="$data/water_n$1.glb" log="$data/render_n$1_x$2.log"
  (cd "$data" && /usr/bin/time -v "$here/target/release/caustic" render box.lua \
    -D "MESH=$(basename "$glb")" -D "COPIES=$copies" --stats -o "box_n${n}_x$copies.png") \
    >"$log" 2>&1 || { cat "$log" >&2; exit 1; }
  awk -v n="$n" -v k="$copies" -v file="$(stat -c %s "$glb")" '
    /triangles: .* placed/ { placed = $2; tris = $4; bvh = $(NF-4); build = $(NF-1) }
    /^wrote .* in / { wall = $(NF-1) }
    /Maximum resident set size/ { kib = $NF }
    END {
      what = sprintf("n = %d, %d triangles", n, tris)
      if (k > 1) what = what sprintf(" placed %d times (%d placed)", k, placed)
      printf "| %s | %.0f MB GLB | %.1f s | %.0f MB (%.1f B/tri) | %.2f GiB | %.0f B | %s s |\n",
        what, file / 1e6, build, bvh / 1e6, bvh / tris, kib / 1048576, kib * 1024 / tris, wall
    }' "$log"
}
for n in $sizes; do
  [ -f "$data/water_n$n.glb" ] || target/release/water --n "$n" --size 2.1 --amplitude 0.012 \
    --wavelength 0.45 --spread 1.2 --seed 7 --depth 0.85 -o "$data/water_n$n.glb" >/dev/null
  row "$n" 1
done
# Instances cost their transform: the first size placed four times.
row "${sizes%% *}" 4
echo
echo "(images and logs in $data)"

((rounds > 0)) || exit 0
if [ ! -f /usr/include/embree3/rtcore.h ] || [ ! -f "$bench/embree_bench.c" ]; then
  echo "no Embree 3 (apt-get install -y libembree-dev) or no harness at $bench: build rounds skipped"
  exit 0
fi
mkdir -p "$data/bin"
[ -x "$data/bin/gen" ] || gcc -O2 -Wall -o "$data/bin/gen" "$bench/gen.c" -lm
[ -x "$data/bin/embree_bench" ] ||
  gcc -O3 -march=native -Wall -o "$data/bin/embree_bench" "$bench/embree_bench.c" -lembree3 -lm -lpthread
rays="$data/primary_16x16.rays"
[ -f "$rays" ] || "$data/bin/gen" primary 16 16 "$rays" >/dev/null 2>&1
builds="$data/builds.txt"
: >"$builds"
for n in $sizes; do
  mesh="$data/wave_N$n.mesh"
  [ -f "$mesh" ] || "$data/bin/gen" mesh "$n" "$mesh" >/dev/null 2>&1
  for ((r = 1; r <= rounds; r++)); do
    if ((r % 2)); then order="embree caustic"; else order="caustic embree"; fi
    for e in $order; do
      if [ "$e" = embree ]; then
        for t in 1 0; do
          "$data/bin/embree_bench" --quality medium --build-reps 1 --threads "$t" --build-only "$mesh"
        done
      else
        target/release/bench_traversal --build-reps 1 --reps 1 --mt 0 --verify 0 "$mesh" "$rays"
      fi | awk -v n="$n" -v r="$r" '/^BUILD/ {
          for (i = 2; i <= NF; i++) { split($i, kv, "="); v[kv[1]] = kv[2] }
          t = v["threads"] == 1 ? v["build_cpu_ms_min"] : v["build_ms_min"]
          print n, r, v["engine"], v["threads"], t
        }' >>"$builds"
    done
  done
done
echo
echo "Builds of the wave mesh (quality medium for Embree, binned SAH both), ms: 1 thread by CPU time,"
echo "2 threads by wall time; caustic / Embree per round"
echo
echo "| N | triangles | round | Embree 1 thr | caustic 1 thr | ratio | Embree 2 thr | caustic 2 thr | ratio |"
echo "|---|---|---|---|---|---|---|---|---|"
awk '{ t[$1, $2, $3, $4] = $5; seen[$1, $2] = 1; ns[$1] = 1; rs[$2] = 1 }
  END {
    for (k in seen) {
      split(k, kk, SUBSEP); n = kk[1]; r = kk[2]
      e1 = t[n, r, "embree3", 1]; c1 = t[n, r, "caustic", 1]
      e0 = t[n, r, "embree3", 0]; c0 = t[n, r, "caustic", 0]
      printf "| %d | %d | %d | %.0f | %.0f | %.2f | %.0f | %.0f | %.2f |\n",
        n, 2 * (n - 1) * (n - 1), r, e1, c1, c1 / e1, e0, c0, c0 / e0
    }
  }' "$builds" | sort -t'|' -k2,2n -k4,4n
