#!/usr/bin/env bash
# Structural changes must not move a bit: renders a fixed set of scenes with both integrators
# and every instruction set this CPU has (ISAS, default "avx512 avx2 scalar"; a set the CPU
# lacks falls back to the next) to PFM and traces fixed ray files, with the given binary,
# into OUT. Compare two such folders
# with `cmp` (the `compare` form does it).
#
#   tools/invariants.sh make target/release/wavepath /tmp/inv-new
#   tools/invariants.sh compare /tmp/inv-old /tmp/inv-new
set -euo pipefail
S="${WAVEPATH_SCENES:-$(cd "$(dirname "$0")/../.." && pwd)/shared/scenes}"

case "${1:-}" in
make)
  BIN="$2"; OUT="$3"; mkdir -p "$OUT"
  scenes=(
    "default|"
    "CBbunny|$S/cs184/sky/CBbunny.dae"
    "CBspheres_lambertian|$S/cs184/sky/CBspheres_lambertian.dae"
    "CBspheres|$S/cs184/sky/CBspheres.dae"
    "CBbunny_microfacet_cu|$S/cs184/sky/CBbunny_microfacet_cu.dae"
    "CBlucy|$S/cs184/reconstructed/sky/CBlucy.dae"
    "gltf_cornell|$S/gltf/CornellBox-Original/CornellBox-Original.gltf"
    "obj_cornell_sphere|$S/obj/CornellBox/CornellBox-Sphere.obj"
  )
  for entry in "${scenes[@]}"; do
    name="${entry%%|*}"; file="${entry#*|}"
    for integ in wavefront recursive; do
      for isa in ${ISAS:-avx512 avx2 scalar}; do
        "$BIN" -t 2 -s 4 -l 2 -m 5 -r 80 60 --integrator "$integ" --isa "$isa" -f "$OUT/$name-$integ-$isa.pfm" $file >/dev/null 2>&1 \
          || { echo "render failed: $name $integ $isa" >&2; exit 1; }
      done
    done
  done
  for mesh in "$S/meshes/lucy_100k.obj" "$S/meshes/dragon_100k.ply"; do
    m=$(basename "$mesh"); m="${m%.*}"
    for kind in primary diffuse; do
      "$BIN" rays dump "$mesh" --kind "$kind" --out "$OUT/$m-$kind.rays" -r 256 192 >/dev/null 2>&1
      "$BIN" rays trace "$mesh" "$OUT/$m-$kind.rays" -t 2 -r 1 -o "$OUT/$m-$kind.hits" >/dev/null 2>&1
      rm -f "$OUT/$m-$kind.rays"
    done
  done
  ls "$OUT" | wc -l
  ;;
compare)
  status=0
  for f in "$2"/*; do
    n=$(basename "$f")
    if ! cmp -s "$f" "$3/$n"; then echo "DIFFERS: $n"; status=1; fi
  done
  [ $status = 0 ] && echo "all $(ls "$2" | wc -l) files identical"
  exit $status
  ;;
*) sed -n 2,8p "$0"; exit 2 ;;
esac
