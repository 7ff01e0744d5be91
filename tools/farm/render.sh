#!/bin/bash
# The tiles of a render farm, as a Slurm job array that starts once the photon pass has
# succeeded: task i renders band i of TILES horizontal bands of the WIDTH x HEIGHT image,
# reading maps.bin instead of tracing its own maps.
#   sbatch --dependency=afterok:$jid --array=0-$((TILES - 1)) \
#       --export=ALL,SCENE=scene.lua,WIDTH=1024,HEIGHT=1024,TILES=8 tools/farm/render.sh
# and at the end `caustic stitch tile*.png -o scene.png`. FLAGS and CAUSTIC as for photons.sh.
#SBATCH --job-name=caustic-tile
#SBATCH --cpus-per-task=2
set -euo pipefail
i=$SLURM_ARRAY_TASK_ID
y0=$((i * HEIGHT / TILES))
y1=$(((i + 1) * HEIGHT / TILES))
"${CAUSTIC:-caustic}" render "$SCENE" -q --threads "${SLURM_CPUS_PER_TASK:-2}" ${FLAGS:-} \
    --photon-maps maps.bin --crop "0,$y0,$WIDTH,$y1" -o "tile$i.png"
