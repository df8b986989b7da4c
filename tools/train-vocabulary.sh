#!/usr/bin/env bash
# Trains heslam's default ORB vocabulary (k 10, L 6) the way the build does (target
# heslam-default-vocabulary, output build/vocabulary/heslam_orb.hvoc). Inputs, all freely available:
#   - the photographs of Debian's opencv-doc (/usr/share/doc/opencv-doc/examples),
#   - frames rendered by heslam-synth from every preset in config/synth/, seeds 9001.. (the tests
#     use seeds below 100), every 10th frame,
#   - every 5th left image of ../shared/data/euroc_v101_head when present. NOT euroc_mh01_handheld:
#     it is the relocalization and place-recognition test clip, training on it would flatter them.
# The tree is clustered from a 400,000-descriptor sample (seed 1); word weights use every image.
# Deterministic: the same inputs give the same file. Usage:
#   tools/train-vocabulary.sh [--vocab-bin build/bin/heslam-vocab] [--shared-data ../shared/data]
#                             [--out build/vocabulary/heslam_orb.hvoc] [--threads 2]
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
vocab_bin=$root/build/bin/heslam-vocab
shared_data=$root/../shared/data
out=$root/build/vocabulary/heslam_orb.hvoc
threads=2
while [[ $# -gt 0 ]]; do
  case $1 in
    --vocab-bin) vocab_bin=$2; shift 2 ;;
    --shared-data) shared_data=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    -h|--help) sed -n '2,14p' "$0"; exit 0 ;;
    *) echo "train-vocabulary.sh: unknown argument '$1'" >&2; exit 1 ;;
  esac
done
[[ -x $vocab_bin ]] || { echo "train-vocabulary.sh: $vocab_bin not built (tools/build.sh)" >&2; exit 1; }

sources=()
photos=/usr/share/doc/opencv-doc/examples
if [[ -d $photos ]]; then
  sources+=(--images "$photos")
else
  echo "train-vocabulary.sh: $photos missing (Debian package opencv-doc), training without it" >&2
fi
synth=()
seed=9001
for preset in "$root"/config/synth/*.yaml; do
  synth+=("$(basename "$preset" .yaml):$seed")
  seed=$((seed + 1))
done
sources+=(--synth "${synth[@]}" --synth-step 10)
if [[ -d $shared_data/euroc_v101_head ]]; then
  sources+=(--dataset "$shared_data/euroc_v101_head" --dataset-step 5)
fi

start=$(date +%s)
"$vocab_bin" train "${sources[@]}" --out "$out" --k 10 --levels 6 --features 1200 --seed 1 \
  --threads "$threads" --max-descriptors 400000
echo "train-vocabulary.sh: $out in $(( $(date +%s) - start )) s"
