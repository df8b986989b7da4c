#!/usr/bin/env bash
# The one-command demo: installs missing Debian packages, builds heslam, generates the synthetic `room`
# sequence (cached in build/data), runs the stereo pipeline on it in lockstep under heslam-supervisor
# (replay -> frontend -> local mapper -> loop closer -> recorder, config/pipelines/synth.yaml) with
# heslam-viewer attached (windows when there is a display, else headless) and prints the ATE against the
# ground truth; the viewer's final map picture lands beside the error plot.
#   HESLAM_BUILD_DIR  build folder (default build/)       HESLAM_DEMO_FRAMES  frames to render (default 300)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build_dir=${HESLAM_BUILD_DIR:-$root/build}
frames=${HESLAM_DEMO_FRAMES:-300}
bin=$build_dir/bin

"$root/tools/build.sh" --demo  # the programs below only; tools/test.sh builds the rest

# Rendering takes a while: reuse a finished sequence (the marker is written only after success).
dataset=$build_dir/data/room_$frames
if [[ ! -f $dataset/.complete ]]; then
  echo "heslam demo: rendering the synthetic 'room' sequence ($frames frames) into $dataset"
  rm -rf "$dataset"
  "$bin/heslam-synth" --preset room --frames "$frames" --threads 2 --out "$dataset"
  touch "$dataset/.complete"
else
  echo "heslam demo: using the cached sequence $dataset"
fi

output_dir=$build_dir/demo
mkdir -p "$output_dir"
trajectory=$output_dir/room_trajectory.txt
echo "heslam demo: running config/pipelines/synth.yaml (the full system, lockstep)"
"$bin/heslam-supervisor" "$root/config/pipelines/synth.yaml" --log-dir "$output_dir/logs" \
  --arg dataset="$dataset" --arg output="$trajectory" --arg viewer=heslam-viewer

echo
echo "heslam demo: trajectory $trajectory ($(grep -vc '^#' "$trajectory") poses; untracked frames listed in" \
     "${trajectory%.txt}.lost.txt)"
# The recorder writes body-frame poses (the ground truth's frame; '# heslam frame: body' in the file).
"$bin/heslam-eval" ape --gt "$dataset/mav0/state_groundtruth_estimate0/data.csv" \
  --est "$trajectory" --plot "$output_dir/room_ate.svg"
echo "heslam demo: top view and error plot in $output_dir/room_ate.svg"
viewer_dir=${trajectory%.txt}.viewer  # a run's outputs: OUTPUT stem + .map, .loop, .viewer (docs/recorder.md)
if [[ -f $viewer_dir/map_final.png ]]; then
  cp "$viewer_dir/map_final.png" "$output_dir/room_map.png"
  cp "$viewer_dir/frame_final.png" "$output_dir/room_last_frame.png"
  echo "heslam demo: the viewer's final map $output_dir/room_map.png and last frame $output_dir/room_last_frame.png" \
       "(all its pictures in $viewer_dir/)"
else
  echo "heslam demo: the viewer left no picture (see $output_dir/logs/viewer.log)"
fi
