#!/usr/bin/env bash
# Renders every scene in scenes/ and in the corpus at a small size through the CLI, with a few
# variants of the render modes, and prints one line per image: scene, variant, exit status and
# the hash of each film made (through CAUSTIC_FILM_LOG, see src/render/film_log.rs).
#
#   bash tools/golden.sh > before.txt   # on the old tree
#   bash tools/golden.sh > after.txt    # on the new tree
#   diff before.txt after.txt           # a refactor that must not change images: no output
#
# Needs a release build (cargo build --release --workspace). Scenes whose corpus is absent are
# skipped with one line.
set -uo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${BIN:-$root/target/release/caustic}
corpus=$root/../shared/corpus/cs488
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# One render: a label, the working directory, then the caustic arguments.
one() {
  local label=$1 dir=$2
  shift 2
  local log=$work/films.log
  rm -f "$log"
  local status
  (cd "$dir" && CAUSTIC_FILM_LOG=$log "$bin" "$@" -q >"$work/out" 2>"$work/err")
  status=$?
  local films
  films=$(if [ -f "$log" ]; then sed 's/^main\[[^]]*\]//' "$log" | tr '\n' ' '; fi)
  echo "$label status=$status ${films:-no-film}"
}

small=(--scale 0.125 --photon-scale 0.05)

# The project's own scenes (with their textures; generated meshes in a cache that persists).
tree=$work/tree
mkdir -p "$tree/scenes"
cp "$root"/scenes/*.lua "$tree/scenes/"
cp -r "$root"/scenes/textures "$root"/scenes/lib "$tree/scenes/"
export CAUSTIC_CACHE=${CAUSTIC_CACHE:-$root/target/golden-mesh-cache}
for s in "$tree"/scenes/*.lua; do
  n=$(basename "$s" .lua)
  one "scenes/$n" "$tree" render "scenes/$n.lua" "${small[@]}" -o "$work/$n.png"
done
one "scenes/cornell_glass direct" "$tree" render scenes/cornell_glass.lua "${small[@]}" --indirect direct -o "$work/x.png"
one "scenes/cornell_glass estimate" "$tree" render scenes/cornell_glass.lua "${small[@]}" --gather-lookup estimate -o "$work/x.png"
one "scenes/cornell_glass spp4" "$tree" render scenes/cornell_glass.lua "${small[@]}" --spp 4 --gather-rays 8 -o "$work/x.png"
one "scenes/cornell_glass adaptive" "$tree" render scenes/cornell_glass.lua "${small[@]}" --adaptive --gather-rays 8 -o "$work/x.png"
one "scenes/cornell_glass crop" "$tree" render scenes/cornell_glass.lua "${small[@]}" --crop 3,4,20,30 -o "$work/x.png"
one "scenes/cornell_glass photons" "$tree" photons scenes/cornell_glass.lua --scale 0.125 --photons 20000 -o "$work/x.png"

if [ ! -d "$corpus" ]; then
  echo "skipped: the corpus ($corpus is absent)"
  exit 0
fi
# Each corpus script runs from the folder its project runs it from (PROVENANCE.md).
while read -r script dir; do
  one "corpus/$script" "$corpus/$dir" render "$corpus/$script" "${small[@]}" -o "$work/c.png"
  one "corpus/$script gi-on" "$corpus/$dir" render "$corpus/$script" "${small[@]}" --gi on --gather-rays 4 -o "$work/c.png"
done <<'LIST'
shraacha__cs488/A4/Assets/simple.lua shraacha__cs488/A4/Assets
shraacha__cs488/A4/Assets/nonhier.lua shraacha__cs488/A4/Assets
shraacha__cs488/A4/Assets/nonhier2.lua shraacha__cs488/A4/Assets
shraacha__cs488/A4/Assets/hier.lua shraacha__cs488/A4/Assets
shraacha__cs488/A4/Assets/instance.lua shraacha__cs488/A4/Assets
shraacha__cs488/A4/Assets/simple-cows.lua shraacha__cs488/A4/Assets
shraacha__cs488/A4/Assets/macho-cows.lua shraacha__cs488/A4/Assets
tengyucai__Computer-Graphics/Project/Assets/bump.lua tengyucai__Computer-Graphics/Project
tengyucai__Computer-Graphics/Project/Assets/csg.lua tengyucai__Computer-Graphics/Project
tengyucai__Computer-Graphics/Project/Assets/cylinder.lua tengyucai__Computer-Graphics/Project
tengyucai__Computer-Graphics/Project/Assets/perlin.lua tengyucai__Computer-Graphics/Project
tengyucai__Computer-Graphics/Project/Assets/refraction.lua tengyucai__Computer-Graphics/Project
tengyucai__Computer-Graphics/Project/Assets/room2.lua tengyucai__Computer-Graphics/Project
tengyucai__Computer-Graphics/Project/Assets/texture.lua tengyucai__Computer-Graphics/Project
dsu1995__raytracer-cpp/tracer/Assets/primitives.lua dsu1995__raytracer-cpp/tracer/Assets
qaovxtazypdl__Raytracer/A5/Assets/CSG.lua qaovxtazypdl__Raytracer/A5
qaovxtazypdl__Raytracer/A5/Assets/AreaLight.lua qaovxtazypdl__Raytracer/A5
mismayil__cs488/A5/Assets/primitives.lua mismayil__cs488/A5
zaalsabb__cs488/A5/Assets/objective8b.lua zaalsabb__cs488/A5/Assets
WeiqiangYu0528__cs488/A5/Assets/primitive.lua WeiqiangYu0528__cs488/A5/Assets
LIST
one "corpus/room2 direct" "$corpus/tengyucai__Computer-Graphics/Project" render "$corpus/tengyucai__Computer-Graphics/Project/Assets/room2.lua" "${small[@]}" --indirect direct -o "$work/c.png"
one "corpus/room2 estimate" "$corpus/tengyucai__Computer-Graphics/Project" render "$corpus/tengyucai__Computer-Graphics/Project/Assets/room2.lua" "${small[@]}" --gather-lookup estimate --gather-rays 8 -o "$work/c.png"
