#!/bin/bash
# The photon pass of a render farm, as a Slurm job: traces the photon maps (and the irradiance
# cache) once, for every tile of tools/farm/render.sh to read. Submit it first:
#   jid=$(sbatch --parsable --export=ALL,SCENE=scene.lua tools/farm/photons.sh)
# SCENE is the script; FLAGS (optional) the render flags every job shares (--scale, --seed,
# photon counts: the tiles must get the same); CAUSTIC the binary (default: caustic on PATH).
#SBATCH --job-name=caustic-photons
#SBATCH --cpus-per-task=2
set -euo pipefail
"${CAUSTIC:-caustic}" photons "$SCENE" -q --threads "${SLURM_CPUS_PER_TASK:-2}" ${FLAGS:-} \
    --save maps.bin
