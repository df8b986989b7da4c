#!/usr/bin/env bash
# Time to first result on a fresh Debian 12 machine: tools/demo.sh in a new Debian 12 (bookworm) chroot
# made by debootstrap, nothing installed but the minimal base, git and ca-certificates, ccache off.
# Needs root, debootstrap (apt-get install debootstrap) and the Debian mirror. Usage:
#   tools/bench/fresh_machine.sh [--ref REF] [--work DIR] [--mirror URL] [--keep]
#     --ref     the commit to clone (default HEAD of this checkout)
#     --work    where the chroots live (default /var/tmp/heslam-fresh): base/ is the debootstrap base,
#               made once and reused; run-COMMIT/ is a copy of it per measurement, removed at the end
#               unless --keep; the step logs, times and .ninja_log are kept in logs-COMMIT/
# Inside the copy it clones this checkout to /root/heslam and runs, timed one after the other, the three
# steps tools/demo.sh takes (their sum is what `time tools/demo.sh` takes on that machine):
#   1. tools/install-deps.sh demo   apt alone: update + the demo's packages (network and dpkg bound)
#   2. tools/build.sh --demo        configure + build heslam-demo + train the vocabulary (CPU bound)
#   3. tools/demo.sh                the build is up to date: render the room, run the pipeline, ATE
# and prints each step's wall, user and sys seconds, the sum, and the load average before and after:
# on a shared machine the wall times are upper bounds, user+sys is what the build costs.
# /proc, /sys and /dev are mounted into the chroot (private mounts, nothing propagates to the host) and
# unmounted on every exit.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
ref=HEAD
work=/var/tmp/heslam-fresh
mirror=http://deb.debian.org/debian
keep=0
while [[ $# -gt 0 ]]; do
  case $1 in
    --ref) ref=$2; shift 2 ;;
    --work) work=$2; shift 2 ;;
    --mirror) mirror=$2; shift 2 ;;
    --keep) keep=1; shift ;;
    -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
    *) echo "fresh_machine.sh: unknown argument '$1'" >&2; exit 1 ;;
  esac
done
[[ $(id -u) -eq 0 ]] || { echo "fresh_machine.sh: needs root (debootstrap, chroot, mount)" >&2; exit 1; }
if ! command -v debootstrap >/dev/null; then
  echo "fresh_machine.sh: needs debootstrap (apt-get install debootstrap)" >&2
  exit 1
fi
commit=$(git -C "$root" rev-parse --verify "$ref^{commit}")

base=$work/base
run=$work/run-${commit:0:10}  # one per commit: two commits can be measured side by side
logs=$work/logs-${commit:0:10}
mounted=()
cleanup() {
  local i
  for ((i = ${#mounted[@]} - 1; i >= 0; i--)); do
    umount "${mounted[i]}" 2>/dev/null || umount -l "${mounted[i]}" ||
      echo "fresh_machine.sh: could not unmount ${mounted[i]}" >&2
  done
  mounted=()
  if [[ -d $run/root ]]; then
    mkdir -p "$logs"
    cp "$run"/root/times "$run"/root/*.log "$run"/root/heslam/build/.ninja_log "$logs/" 2>/dev/null || true
  fi
  if ((keep == 0)) && [[ -d $run ]]; then
    if grep -q " $run/" /proc/mounts; then
      echo "fresh_machine.sh: $run still has mounts, not removed" >&2
    else
      rm -rf "$run"
    fi
  fi
}
trap cleanup EXIT
trap 'exit 130' INT TERM

mkdir -p "$work"
if [[ ! -f $base/.complete ]]; then
  echo "fresh_machine.sh: debootstrap bookworm into $base (once)"
  rm -rf "$base"
  debootstrap --variant=minbase --include=git,ca-certificates bookworm "$base" "$mirror" >"$work/debootstrap.log"
  # What a Debian 12 install lists: the release, its updates and the security archive.
  cat >"$base/etc/apt/sources.list" <<EOF
deb $mirror bookworm main
deb $mirror bookworm-updates main
deb ${mirror%/debian}/debian-security bookworm-security main
EOF
  chroot "$base" apt-get clean
  rm -rf "$base"/var/lib/apt/lists/*
  touch "$base/.complete"
fi

if grep -q " $run/" /proc/mounts; then
  echo "fresh_machine.sh: $run has mounts left from an earlier run; unmount them first" >&2
  exit 1
fi
rm -rf "$run"
cp -a "$base" "$run"
cp /etc/resolv.conf "$run/etc/resolv.conf"
bind_private() {  # bind_private SOURCE TARGET: a bind mount that shares no mount events with the host
  mount --bind "$1" "$2"
  mounted+=("$2")
  mount --make-private "$2"
}
mount -t proc proc "$run/proc"
mounted+=("$run/proc")
bind_private /sys "$run/sys"
bind_private /dev "$run/dev"
mount -t tmpfs -o mode=1777 shm "$run/dev/shm"
mounted+=("$run/dev/shm")

git clone -q --no-local "$root" "$run/root/heslam"
git -C "$run/root/heslam" checkout -q "$commit"
echo "fresh_machine.sh: $commit in $run/root/heslam; $(nproc) cores; load before: $(cut -d' ' -f1-3 /proc/loadavg)"

# A login's environment, nothing of this shell's; ccache off so nothing comes from an earlier build.
chroot "$run" /usr/bin/env -i HOME=/root PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
  LANG=C.UTF-8 CCACHE_DISABLE=1 /bin/bash -c '
set -euo pipefail
cd /root/heslam
TIMEFORMAT="%R %U %S"
step() {  # step NAME COMMAND...: runs it, log in /root/NAME.log, "NAME wall user sys" to /root/times
  local t
  if ! t=$( { time "${@:2}" >"/root/$1.log" 2>&1; } 2>&1 ); then
    echo "step $1 failed:"
    tail -20 "/root/$1.log"
    exit 1
  fi
  echo "$1 $t" >>/root/times
}
: >/root/times
step apt tools/install-deps.sh demo
if grep -q -- "--demo" tools/build.sh; then
  step build tools/build.sh --demo
else  # a commit before tools/build.sh --demo
  step build tools/build.sh heslam-demo
fi
step demo tools/demo.sh
grep -iE "ate|rmse|poses" /root/demo.log || true
'
echo "fresh_machine.sh: load after: $(cut -d' ' -f1-3 /proc/loadavg)"
awk '{ printf "%-6s wall %7.1f s  user %7.1f s  sys %6.1f s\n", $1, $2, $3, $4; w += $2; c += $3 + $4 }
     END { printf "total  wall %7.1f s (%.1f min)  user+sys %.1f s\n", w, w / 60, c }' "$run/root/times"
echo "fresh_machine.sh: logs in $logs/ (apt.log, build.log, demo.log, times, .ninja_log)"
