#!/usr/bin/env bash
# What the pipeline needs from a network between two hosts (docs/deployment.md), measured over a veth
# link between two network namespaces made here (root and `ip netns` needed; removed on exit):
#  1. per-frame transport latency of a stereo pair from heslam-replay on host A to a subscriber on
#     host B (heslam-bench-transport --replay-via), and on loopback for comparison;
#  2. bytes per second and messages per second of every topic seen from host B (heslam-spy bw) while
#     the full system runs in real time split over the hosts (camera: replay, frontend, recorder;
#     server: local mapper, loop closer): the keyframe and map-point throughput, and the budget a
#     real network must give.
#   sudo tools/bench/multihost_link.sh [--dataset DIR] [--frames N] [--domain N] [--out DIR]
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
bin=$root/build/bin
dataset=$root/../shared/data/euroc_mh01_handheld
frames=200 domain=${HESLAM_DOMAIN:-171} out=""
while [[ $# -gt 0 ]]; do
  case $1 in
    --dataset) dataset=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --domain) domain=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    *) echo "usage: $0 [--dataset DIR] [--frames N] [--domain N] [--out DIR]" >&2; exit 1 ;;
  esac
done
[[ $(id -u) -eq 0 ]] || { echo "multihost_link.sh: needs root (ip netns)" >&2; exit 1; }
[[ -d $dataset/mav0 ]] || { echo "multihost_link.sh: $dataset: not an EuRoC folder" >&2; exit 1; }
out=${out:-$(mktemp -d /tmp/heslam-multihost-XXXXXX)}
mkdir -p "$out"

a=hslb$$a b=hslb$$b
cleanup() { ip netns del "$a" 2>/dev/null || true; ip netns del "$b" 2>/dev/null || true; }
trap cleanup EXIT
ip netns add "$a"; ip netns add "$b"
ip link add "hb$$a" type veth peer name "hb$$b"
ip link set "hb$$a" netns "$a"; ip link set "hb$$b" netns "$b"
ip -n "$a" link set "hb$$a" name hsnet0; ip -n "$b" link set "hb$$b" name hsnet0
ip -n "$a" addr add 10.213.8.1/24 dev hsnet0; ip -n "$b" addr add 10.213.8.2/24 dev hsnet0
for ns in "$a" "$b"; do ip -n "$ns" link set hsnet0 up; ip -n "$ns" link set lo up; done
net=(--arg dds_profile=network --arg dds_interface=hsnet0 --arg dds_peers=10.213.8.1,10.213.8.2)
echo "veth link: $(ip -n "$a" link show hsnet0 | grep -o 'mtu [0-9]*'), load before: $(cut -d' ' -f1-3 /proc/loadavg)"

# ---- 2. topics over the link during a real-time run ----
topics=(camera/stereo camera/calibration odometry map/keyframes map/keyframe_states map/points loop/corrections
        lockstep/frame_done lockstep/keyframe_done system/status)
pipeline=$root/config/pipelines/euroc_realtime.yaml
ip netns exec "$b" "$bin/heslam-supervisor" "$pipeline" --host server --domain "$domain" "${net[@]}" \
  --arg output="$out/rt.txt" --log-dir "$out/logs_server" > "$out/server.out" 2> "$out/server.err" &
server=$!
sleep 1  # the server half writes the network profile's XML into its log folder first
xml=file://$out/logs_server/cyclonedds-network.xml
spies=()
for topic in "${topics[@]}"; do
  ip netns exec "$b" "$bin/heslam-spy" bw "$topic" --window 100000 --domain "$domain" --dds-config "$xml" \
    > "$out/bw_${topic//\//_}.txt" 2>&1 &
  spies+=($!)
done
start=$(date +%s.%N)
ip netns exec "$a" "$bin/heslam-supervisor" "$pipeline" --host camera --domain "$domain" "${net[@]}" \
  --arg dataset="$dataset" --arg output="$out/rt.txt" --log-dir "$out/logs_camera" > "$out/camera.out" 2> "$out/camera.err"
end=$(date +%s.%N)
wait "$server" || true
for pid in "${spies[@]}"; do kill -INT "$pid" 2>/dev/null || true; done
wait "${spies[@]}" 2>/dev/null || true
echo "real-time run over the link: $(tail -n 1 "$out/camera.err" | sed 's/.*info: //'); $(awk -v s="$start" -v e="$end" 'BEGIN { printf "%.1f s", e - s }')"
grep -h "processed .* frames\|frames missed\|mapped .* keyframes\|map: " "$out"/logs_*/frontend.log "$out"/logs_*/local_mapper.log | sed 's/^/  /'
printf '%-24s %12s %10s %14s\n' topic "bytes/s" "messages" "message size"
for topic in "${topics[@]}"; do
  f=$out/bw_${topic//\//_}.txt
  rate=$(grep -E '/s from [0-9]+ messages' "$f" | tail -n 1 | awk '{print $1, $2}' || true)
  count=$(grep -E '/s from [0-9]+ messages' "$f" | tail -n 1 | awk '{print $4}' || true)
  size=$(grep 'message size mean' "$f" | tail -n 1 | awk '{print $4, $5}' || true)
  printf '%-24s %12s %10s %14s\n' "$topic" "${rate:--}" "${count:-0}" "${size:--}"
done

# ---- 1. stereo-pair latency over the link, then on loopback ----
echo "stereo pair latency, replay on host A -> subscriber on host B (veth, network profile):"
CYCLONEDDS_URI=$xml ip netns exec "$b" "$bin/heslam-bench-transport" --frames "$frames" --domain "$domain" \
  --replay-via "ip netns exec $a" --no-plain-c --ddsperf-seconds 0 | tail -n 5
echo "the same on loopback (built-in XML):"
"$bin/heslam-bench-transport" --frames "$frames" --domain "$domain" --no-plain-c --ddsperf-seconds 0 | tail -n 5
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg); files in $out"
