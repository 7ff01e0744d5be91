#!/usr/bin/env bash
# Renders every scene in scenes/gallery/ at its script's size (each at most 256 pixels wide), and
# the project's scenes listed in $project below at a quarter of theirs, into
# docs/gallery/NAME.png and writes docs/gallery.md: a table of thumbnail, name, what the scene
# shows (the first paragraph of its header comment, without "Gallery: "), the command that
# renders it and how long that took here.
#
#   bash tools/gallery.sh
#
# Builds caustic in release mode first. gr.water_mesh's meshes are cached in scenes/gallery/.cache
# (git-ignored) unless CAUSTIC_CACHE names another folder. The times are wall-clock seconds on
# whatever this machine is doing: informative, not a benchmark.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
cargo build --release --quiet --bin caustic
bin=$root/target/release/caustic
out=docs/gallery
mkdir -p "$out"
rm -f "$out"/*.png

# The first paragraph of a script's header comment, on one line, capitalised.
describe() {
  awk '!/^--/ || /^-- *$/ { exit }
       { sub(/^-- ?/, ""); if (NR == 1) { sub(/^Gallery: /, ""); $0 = toupper(substr($0, 1, 1)) substr($0, 2) } printf "%s%s", (NR > 1 ? " " : ""), $0 }' "$1"
}

rows=""
# The gallery's scenes at their size, then the project's scenes named here at a quarter of theirs.
project="scenes/underwater.lua"
for scene in scenes/gallery/*.lua $project; do
  name=$(basename "$scene" .lua)
  flags=()
  case " $project " in *" $scene "*) flags=(--scale 0.25) ;; esac
  log=$("$bin" render "$scene" "${flags[@]}" -q -o "$out/$name.png" 2>&1 >/dev/null) || {
    echo "gallery: $scene failed:" >&2
    echo "$log" >&2
    exit 1
  }
  seconds=$(sed -n 's/^wrote .* in \([0-9.]*\) s$/\1/p' <<<"$log")
  size=$(sed -n 's/^wrote .* (\([0-9]*x[0-9]*\)) in .*$/\1/p' <<<"$log")
  echo "gallery: $name ($size) in $seconds s" >&2
  rows+="| ![$name](gallery/$name.png) | [\`$name\`](../$scene) | $(describe "$scene") | \`caustic render $scene${flags[*]:+ ${flags[*]}}\` | $seconds s |"$'\n'
done

cat >docs/gallery.md <<EOF
# Gallery

One small scene per capability of caustic, in [\`scenes/gallery/\`](../scenes/gallery/). Each
script starts with a comment saying what it shows; copy one to start a scene of your own. From
the repository's root, \`cargo run --release -- render scenes/gallery/NAME.lua\` writes
\`NAME.png\` into the working directory; the scripts find their meshes and textures from their
own folder, so they also render from inside it. \`tests/command_line/gallery.rs\` renders every
one at a quarter of its size and checks what it shows.

The thumbnails are the scripts' own size and default settings (the last rows, scenes of the
project, a quarter of theirs). Regenerate them and this page
with \`bash tools/gallery.sh\`. Times are wall-clock seconds of one render on the machine that
last ran it ($(nproc) cores$([ -n "${GALLERY_MACHINE:-}" ] && printf ', %s' "$GALLERY_MACHINE")):
informative, not a benchmark.

| image | scene | what it shows | command | time |
|---|---|---|---|---|
$rows
EOF
echo "gallery: wrote docs/gallery.md and $(ls "$out" | wc -l) thumbnails in $out" >&2
