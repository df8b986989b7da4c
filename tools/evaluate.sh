#!/usr/bin/env bash
# The paper's evaluation in one command (docs/evaluation.md): every KITTI odometry and EuRoC MAV
# sequence found under the given folders runs through the full system (frontend + local mapper +
# loop closer) in lockstep (deterministic; --runs N times) and once in real time (dropped frames);
# then ATE RMSE (SE(3)), the KITTI devkit drift for KITTI, per-frame time median / p90, one Markdown
# and one CSV table with the paper's published numbers beside ours, and a trajectory plot per
# sequence.
set -euo pipefail

usage() {
  cat <<'EOF'
usage: tools/evaluate.sh [--kitti DIR] [--euroc DIR] [--runs N] [--he MODE] [--out DIR]
                         [--loop-closer EXE] [--no-realtime] [--rate R] [--domain N] [--bin DIR] [--list]
  --kitti DIR        KITTI odometry: DIR/sequences/NN/{image_0,image_1,times.txt,calib.txt}, ground
                     truth DIR/poses/NN.txt (or NN/poses.txt, as heslam-synth writes); DIR may also be
                     one sequence folder
  --euroc DIR        EuRoC MAV (ASL layout): every DIR/*/mav0 (or DIR/mav0), ground truth
                     mav0/state_groundtruth_estimate0/data.csv, camera pose = body x T_BS(cam0)
  --runs N           lockstep runs per sequence (default 1); the table gives the mean ATE and says
                     whether the runs were bit-identical
  --he MODE          histogram equalization: none, global (the paper), clipped, clahe, adaptive
                     (default: the frontend's default, clipped)
  --out DIR          results (default: ${XDG_CACHE_HOME:-~/.cache}/heslam/evaluation-YYYYmmdd-HHMMSS,
                     printed as the run starts; never the current folder, which may be the source tree)
  --loop-closer EXE  heslam-loop-closer (default), heslam-loop-closer-proximity or none
  --no-realtime      lockstep only (no real-time run, no dropped-frame count)
  --rate R           real-time run speed (default 1 = the recording's rate)
  --domain N         DDS domain of the runs (default $HESLAM_DOMAIN or 0)
  --bin DIR          heslam binaries (default: build/bin of this tree)
  --list             only list the sequences found (kind, name, folder, ground truth, the paper's
                     HE-SLAM / ORB-SLAM2 ATE when it is one of the paper's sequences); run nothing
At least one of --kitti / --euroc. Exit code 1 when a run fails or no sequence is found.
EOF
}

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
kitti_dirs=() euroc_dirs=()
runs=1 he="" out="" loop_closer=heslam-loop-closer realtime=1 rate=1
domain=${HESLAM_DOMAIN:-0} bin="$root/build/bin" list=0
die() { echo "evaluate.sh: $*" >&2; exit 1; }
while [[ $# -gt 0 ]]; do
  case $1 in
    --kitti) [[ $# -ge 2 ]] || die "--kitti: missing DIR"; kitti_dirs+=("$2"); shift 2 ;;
    --euroc) [[ $# -ge 2 ]] || die "--euroc: missing DIR"; euroc_dirs+=("$2"); shift 2 ;;
    --runs) [[ ${2:-} =~ ^[1-9][0-9]*$ ]] || die "--runs: expected a positive integer, got '${2:-}'"; runs=$2; shift 2 ;;
    --he) [[ ${2:-} =~ ^(none|global|clipped|clahe|adaptive)$ ]] ||
            die "--he: expected none, global, clipped, clahe or adaptive, got '${2:-}'"; he=$2; shift 2 ;;
    --out) [[ -n ${2:-} ]] || die "--out: missing DIR"; out=$2; shift 2 ;;
    --loop-closer) [[ -n ${2:-} ]] || die "--loop-closer: missing value"; loop_closer=$2; shift 2 ;;
    --no-realtime) realtime=0; shift ;;
    --rate) [[ ${2:-} =~ ^[0-9]+([.][0-9]+)?$ ]] || die "--rate: expected a number, got '${2:-}'"; rate=$2; shift 2 ;;
    --domain) [[ ${2:-} =~ ^[0-9]+$ && ${2:-} -le 232 ]] || die "--domain: expected 0..232, got '${2:-}'"; domain=$2; shift 2 ;;
    --bin) [[ -n ${2:-} ]] || die "--bin: missing DIR"; bin=$2; shift 2 ;;
    --list) list=1; shift ;;
    -h|--help) usage; exit 0 ;;
    *) usage >&2; die "unknown argument '$1'" ;;
  esac
done
[[ ${#kitti_dirs[@]} -gt 0 || ${#euroc_dirs[@]} -gt 0 ]] || { usage >&2; die "give --kitti DIR and/or --euroc DIR"; }

# ---- the paper's published numbers (../shared/paper/he-slam.md, Tables I and II: ATE RMSE in m) ----
# Only ATE RMSE is published (the run time is "basically flat so it is not shown"; no drift
# figures). A number is shown only for the real sequence: KITTI by its number AND its ground truth's
# frame count, EuRoC by the official sequence folder name.
declare -A paper_he=(
  [kitti_00]=1.3034 [kitti_01]=10.2217 [kitti_02]=5.74836 [kitti_03]=0.996917 [kitti_04]=0.233628
  [kitti_05]=0.805461 [kitti_06]=0.812416 [kitti_07]=0.500916 [kitti_08]=3.08941 [kitti_09]=3.61144
  [kitti_10]=0.924477
  [MH_01_easy]=0.0410544 [MH_02_easy]=0.0404337 [MH_03_medium]=0.0507298 [MH_04_difficult]=0.105072
  [MH_05_difficult]=0.0520933 [V1_01_easy]=0.0884811 [V1_02_medium]=0.0643252 [V1_03_difficult]=0.0809867
  [V2_01_easy]=0.0625152 [V2_02_medium]=0.0639234 [V2_03_difficult]=0.234987)
declare -A paper_orb=(
  [kitti_00]=1.30345 [kitti_01]=10.8385 [kitti_02]=5.6336 [kitti_03]=0.977166 [kitti_04]=0.163535
  [kitti_05]=0.764564 [kitti_06]=1.05377 [kitti_07]=0.489687 [kitti_08]=3.40213 [kitti_09]=3.87987
  [kitti_10]=1.02258
  [MH_01_easy]=0.0380801 [MH_02_easy]=0.0436409 [MH_03_medium]=0.0405288 [MH_04_difficult]=0.121237
  [MH_05_difficult]=0.0970062 [V1_01_easy]=0.0885614 [V1_02_medium]=0.0630205 [V1_03_difficult]=0.0650267
  [V2_01_easy]=0.0584563 [V2_02_medium]=0.0573975 [V2_03_difficult]=0.236151)
# Frames of KITTI odometry 00-10 (their ground-truth files): a synthetic "sequences/00" is not KITTI 00.
declare -A kitti_frames=([00]=4541 [01]=1101 [02]=4661 [03]=801 [04]=271 [05]=2761 [06]=1101 [07]=1101
                         [08]=4071 [09]=1591 [10]=1201)

# ---- find the sequences: "kind|name|dataset folder|ground truth|paper key" ----
sequences=()
add_kitti() {  # $1 sequence folder, $2 its number or name, $3 ground-truth file (may be absent)
  local gt=$3 key=""
  [[ -f $gt ]] || gt=""
  if [[ -n $gt && -n ${kitti_frames[$2]:-} && $(grep -c . "$gt") -eq ${kitti_frames[$2]} ]]; then key=kitti_$2; fi
  sequences+=("kitti|kitti_$2|$1|$gt|$key")
}
for dir in "${kitti_dirs[@]}"; do
  [[ -d $dir ]] || die "--kitti $dir: no such folder"
  dir=$(cd "$dir" && pwd)
  found=0
  if [[ -d $dir/image_0 ]]; then
    add_kitti "$dir" "$(basename "$dir")" "$dir/poses.txt"; found=1
  fi
  for seq in "$dir"/sequences/*/; do
    [[ -d ${seq}image_0 && -d ${seq}image_1 && -f ${seq}times.txt && -f ${seq}calib.txt ]] || continue
    seq=${seq%/}; n=$(basename "$seq")
    gt=$dir/poses/$n.txt; [[ -f $gt ]] || gt=$seq/poses.txt
    add_kitti "$seq" "$n" "$gt"; found=1
  done
  [[ $found -eq 1 ]] || die "--kitti $dir: no sequence (expected sequences/NN/ with image_0, image_1, times.txt, calib.txt)"
done
for dir in "${euroc_dirs[@]}"; do
  [[ -d $dir ]] || die "--euroc $dir: no such folder"
  dir=$(cd "$dir" && pwd)
  found=0
  for mav in "$dir"/mav0 "$dir"/*/mav0; do
    [[ -f $mav/cam0/data.csv && -f $mav/cam1/data.csv ]] || continue
    seq=$(dirname "$mav"); name=$(basename "$seq")
    gt=$mav/state_groundtruth_estimate0/data.csv; [[ -f $gt ]] || gt=""
    key=""; [[ -v "paper_he[$name]" ]] && key=$name
    sequences+=("euroc|$name|$seq|$gt|$key"); found=1
  done
  [[ $found -eq 1 ]] || die "--euroc $dir: no sequence (expected DIR/mav0 or DIR/*/mav0 with cam0/data.csv, cam1/data.csv)"
done
if [[ $list -eq 1 ]]; then
  for entry in "${sequences[@]}"; do
    IFS='|' read -r kind name dataset gt key <<< "$entry"
    he_paper="" orb_paper=""
    if [[ -n $key ]]; then he_paper=${paper_he[$key]}; orb_paper=${paper_orb[$key]}; fi
    echo "$kind $name $dataset gt=${gt:-none} paper_he_slam=${he_paper:--} paper_orb_slam2=${orb_paper:--}"
  done
  exit 0
fi
for tool in heslam-supervisor heslam-eval; do
  [[ -x $bin/$tool ]] || die "$bin/$tool not found (build first: tools/build.sh, or give --bin DIR)"
done
if [[ -z $out ]]; then
  cache=${XDG_CACHE_HOME:-${HOME:+$HOME/.cache}}
  cache=${cache:-${TMPDIR:-/tmp}}
  out=$cache/heslam/evaluation-$(date +%Y%m%d-%H%M%S)
fi
mkdir -p "$out" || die "$out: cannot create the results folder"
out=$(cd "$out" && pwd)
echo "evaluate.sh: ${#sequences[@]} sequence(s); lockstep x $runs$([[ $realtime -eq 1 ]] && echo ", real time x 1 at rate $rate"); results in $out"

# ---- settings files with the HE mode ----
settings_file() {  # $1 kitti|euroc -> path of the settings file to run with
  local base=$root/config/camera/$([[ $1 == kitti ]] && echo KITTI00-02 || echo EuRoC).yaml
  if [[ -z $he ]]; then echo "$base"; return; fi
  local copy=$out/settings/$(basename "${base%.yaml}")_he-$he.yaml
  mkdir -p "$out/settings"
  sed "s/^HE.mode:.*/HE.mode: \"$he\"  # set by tools\/evaluate.sh --he/" "$base" > "$copy"
  grep -q "^HE.mode: \"$he\"" "$copy" || { echo "evaluate.sh: $base has no HE.mode line to set" >&2; return 1; }
  echo "$copy"
}

# ---- one run: prints nothing, leaves DIR/trajectory.txt and DIR/logs ----
run_pipeline() {  # $1 kind, $2 mode (lockstep|realtime), $3 dataset, $4 run dir
  local pipeline=$root/config/pipelines/$1$([[ $2 == realtime ]] && echo _realtime).yaml settings
  settings=$(settings_file "$1") || return 1
  local args=(--arg "dataset=$3" --arg "output=$4/trajectory.txt" --arg "loop_closer=$loop_closer"
              --arg "settings=$settings")
  [[ $2 == realtime ]] && args+=(--arg "rate=$rate")
  mkdir -p "$4"
  local started=$SECONDS
  echo "evaluate.sh:   $(basename "$4") ($2) ..."
  if ! "$bin/heslam-supervisor" "$pipeline" --domain "$domain" --log-dir "$4/logs" "${args[@]}" \
       > "$4/supervisor.out" 2> "$4/supervisor.err"; then
    echo "evaluate.sh: $(basename "$3") $2 run failed: $(tail -n 1 "$4/supervisor.err")" >&2
    return 1
  fi
  echo "evaluate.sh:   $(basename "$4") ($2): tracked $(tracked "$4") in $((SECONDS - started)) s"
}

# The frontend's end-of-run "stage total median X ms p90 Y ms" (its last 1000 frames).
frame_time() {  # $1 run dir -> "median p90" in ms, or "- -"
  awk '/stage total/ { for (i = 1; i <= NF; ++i) { if ($i == "median") m = $(i+1); if ($i == "p90") p = $(i+1) } }
       END { if (m == "") print "- -"; else print m, p }' "$1/logs/frontend.log" 2>/dev/null || echo "- -"
}
# Frames published but never processed by the frontend (real time: dropped while it was busy).
dropped_frames() {
  local n
  n=$(grep -o '[0-9]* frames missed' "$1/logs/frontend.log" 2>/dev/null | tail -n 1 | awk '{print $1}' || true)
  echo "${n:-0}"
}
# "tracked N/M" from the supervisor's last line (the recorder's result).
tracked() { grep -o 'tracked [0-9]*/[0-9]*' "$1/supervisor.err" | tail -n 1 | awk '{print $2}' || true; }

ape_args() {  # $1 kind, $2 dataset, $3 gt -> the ground-truth arguments of heslam-eval
  if [[ $1 == euroc ]]; then
    echo "--gt $3"  # the trajectory is of the body frame (the recorder's default), as EuRoC's ground truth
  else
    echo "--gt $3 --gt-times $2/times.txt --gt-format kitti"
  fi
}
json_number() {  # $1 heslam-eval JSON file, $2 dotted key (e.g. translation_m.rmse) -> 6 digits, or "-"
  # heslam-eval writes one key per line, parents before children: follow the path line by line.
  awk -v path="$2" 'BEGIN { n = split(path, part, "."); i = 1 }
    index($0, "\"" part[i] "\":") {
      if (i == n) { v = $0; sub(/.*": */, "", v); sub(/,$/, "", v); printf "%.6g\n", v; found = 1; exit }
      ++i
    }
    END { if (!found) print "-" }' "$1" 2>/dev/null || echo "-"
}
ate() {  # $1 kind, $2 dataset, $3 gt, $4 trajectory, [$5 plot] -> ATE RMSE in m, or "-"
  [[ -n $3 && -s $4 ]] || { echo "-"; return; }
  local json=${4%.txt}.ape.json plot=()
  [[ -n ${5:-} ]] && plot=(--plot "$5")
  # shellcheck disable=SC2046
  if "$bin/heslam-eval" ape $(ape_args "$1" "$2" "$3") --est "$4" --json "$json" "${plot[@]}" > "${4%.txt}.ape.txt" 2>&1; then
    json_number "$json" translation_m.rmse
  else
    # e.g. "the estimate does not move" (a still clip tracked as still cannot be SE(3)-aligned)
    echo "evaluate.sh: $4: no ATE: $(tail -n 1 "${4%.txt}.ape.txt")" >&2
    echo "-"
  fi
}

csv=$out/results.csv
md=$out/results.md
echo "sequence,kind,frames,lockstep_runs,lockstep_identical,tracked_lockstep,ate_rmse_m,ate_rmse_min_m,ate_rmse_max_m,kitti_t_rel_pct,kitti_r_rel_deg_per_100m,frame_ms_median,frame_ms_p90,tracked_realtime,dropped_realtime,ate_rmse_realtime_m,frame_ms_median_realtime,frame_ms_p90_realtime,paper_he_slam_ate_m,paper_orb_slam2_ate_m,plot" > "$csv"
failures=0
index=0
for entry in "${sequences[@]}"; do
  IFS='|' read -r kind name dataset gt key <<< "$entry"
  index=$((index + 1))
  echo "evaluate.sh: [$index/${#sequences[@]}] $name ($kind, $dataset)"
  seq_out=$out/$name
  ates=() digests=() tracked_l="" time_l="- -"
  for ((r = 1; r <= runs; ++r)); do
    run_dir=$seq_out/lockstep_$r
    if ! run_pipeline "$kind" lockstep "$dataset" "$run_dir"; then failures=$((failures + 1)); continue; fi
    plot=""; [[ $r -eq 1 ]] && plot=$seq_out/trajectory.svg
    ates+=("$(ate "$kind" "$dataset" "$gt" "$run_dir/trajectory.txt" "$plot")")
    digests+=("$(sha256sum < "$run_dir/trajectory.txt" | cut -c1-64)")
    if [[ $r -eq 1 ]]; then tracked_l=$(tracked "$run_dir"); time_l=$(frame_time "$run_dir"); fi
  done
  identical="-"
  if [[ ${#digests[@]} -ge 2 ]]; then
    identical=yes
    for d in "${digests[@]}"; do [[ $d == "${digests[0]}" ]] || identical=no; done
  fi
  read -r ate_mean ate_min ate_max <<< "$(printf '%s\n' "${ates[@]:-}" | awk '
    $1 != "-" && $1 != "" { s += $1; n++; if (n == 1 || $1 < lo) lo = $1; if (n == 1 || $1 > hi) hi = $1 }
    END { if (n) printf "%.6g %.6g %.6g\n", s / n, lo, hi; else print "- - -" }')"
  t_rel="-" r_rel="-"
  if [[ $kind == kitti && -n $gt && -s $seq_out/lockstep_1/trajectory.txt ]]; then
    # shellcheck disable=SC2046
    if "$bin/heslam-eval" kitti $(ape_args kitti "$dataset" "$gt") --est "$seq_out/lockstep_1/trajectory.txt" \
         --json "$seq_out/lockstep_1/kitti.json" > "$seq_out/lockstep_1/kitti.txt" 2>&1; then
      t_rel=$(json_number "$seq_out/lockstep_1/kitti.json" translation_error_percent)
      r_rel=$(json_number "$seq_out/lockstep_1/kitti.json" rotation_error_deg_per_100m)
    elif grep -q "no sub-sequence" "$seq_out/lockstep_1/kitti.txt"; then
      t_rel="<100 m" r_rel="<100 m"  # the devkit's shortest sub-sequence is 100 m
    else
      t_rel="error" r_rel="error"
      echo "evaluate.sh: $name: heslam-eval kitti: $(tail -n 1 "$seq_out/lockstep_1/kitti.txt")" >&2
    fi
  fi
  tracked_r="-" dropped="-" ate_r="-" time_r="- -"
  if [[ $realtime -eq 1 ]]; then
    run_dir=$seq_out/realtime
    if run_pipeline "$kind" realtime "$dataset" "$run_dir"; then
      tracked_r=$(tracked "$run_dir"); dropped=$(dropped_frames "$run_dir")
      ate_r=$(ate "$kind" "$dataset" "$gt" "$run_dir/trajectory.txt"); time_r=$(frame_time "$run_dir")
    else
      failures=$((failures + 1))
    fi
  fi
  frames=${tracked_l#*/}
  read -r med p90 <<< "$time_l"; read -r med_r p90_r <<< "$time_r"
  he_paper="" orb_paper=""
  if [[ -n $key ]]; then he_paper=${paper_he[$key]}; orb_paper=${paper_orb[$key]}; fi
  ate_line="ATE lockstep $ate_mean m"; [[ $realtime -eq 1 ]] && ate_line+=", real time $ate_r m"
  echo "evaluate.sh: [$index/${#sequences[@]}] $name: $ate_line"
  echo "$name,$kind,${frames:-},$runs,$identical,${tracked_l:-},$ate_mean,$ate_min,$ate_max,$t_rel,$r_rel,$med,$p90,${tracked_r:-},$dropped,$ate_r,$med_r,$p90_r,$he_paper,$orb_paper,$name/trajectory.svg" >> "$csv"
done

# ---- the Markdown table ----
{
  echo "# heslam evaluation"
  echo
  echo "$(date -u '+%Y-%m-%d %H:%M UTC'), $(nproc) cores, $(uname -n); HE mode: ${he:-frontend default (clipped)}; loop closer: $loop_closer;"
  echo "lockstep runs per sequence: $runs$([[ $realtime -eq 1 ]] && echo "; one real-time run at rate $rate")."
  echo "ATE: RMSE of the translation after SE(3) alignment (EuRoC: left camera = ground-truth body x T_BS(cam0);"
  echo "KITTI: left camera poses). Drift: KITTI devkit, 100..800 m sub-sequences (blank when the run is shorter than 100 m)."
  echo "Frame time: the frontend's per-frame time (its last 1000 frames), median / p90."
  echo "Paper: HE-SLAM paper Tables I and II (ATE RMSE, m); only for the real KITTI 00-10 and EuRoC sequences"
  echo "(the paper publishes no run times or drift figures); blank otherwise."
  echo
  echo "| sequence | frames | tracked (lockstep) | ATE lockstep (m) | runs identical | t_rel (%) | r_rel (deg/100 m) | frame ms median / p90 | real time: tracked | dropped | ATE (m) | frame ms median / p90 | paper HE-SLAM (m) | paper ORB-SLAM2 (m) | plot |"
  echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
  tail -n +2 "$csv" | while IFS=, read -r name kind frames nruns ident tl am amin amax tr rr med p90 trr dr ar medr p90r ph po plot; do
    range=$am; [[ $nruns -gt 1 && $am != "-" ]] && range="$am ($amin-$amax)"
    echo "| $name | $frames | $tl | $range | $ident | $tr | $rr | $med / $p90 | $trr | $dr | $ar | $medr / $p90r | $ph | $po | [svg]($plot) |"
  done
} > "$md"
cat "$md"
echo "evaluate.sh: results in $out (results.md, results.csv, a folder per sequence)"
if [[ $failures -gt 0 ]]; then
  die "$failures run(s) failed (see */supervisor.err under $out)"
fi
