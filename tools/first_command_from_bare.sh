#!/usr/bin/env bash
# Times the README's first command on a bare Debian 12: a minimal system made by debootstrap
# (--variant=minbase: apt and dpkg, no compiler, no package of wlx's), this repository's committed
# main cloned into it, and the command run there as root in a chroot, apt's downloads included.
# The figure the README quotes ("from a bare Debian 12"). Needs root, debootstrap (installed if
# missing) and the Debian archive this machine's apt uses; writes nothing outside FOLDER.
#   tools/first_command_from_bare.sh [FOLDER]     (default: a new folder under /tmp, removed after)
set -euo pipefail
cd "$(dirname "$0")/.."
[ "$(id -u)" -eq 0 ] || { echo "first_command_from_bare.sh: run as root (debootstrap and chroot)" >&2; exit 2; }
keep=false
if [ $# -ge 1 ]; then
  root=$1
  keep=true
  [ ! -e "$root" ] || { echo "first_command_from_bare.sh: $root exists: give a new folder" >&2; exit 2; }
  mkdir -p "$root"
else
  root=$(mktemp -d /tmp/wlx-bare.XXXXXX)
fi
mounted=()
cleanup() {
  for m in "${mounted[@]}"; do umount "$m" 2>/dev/null || true; done
  $keep || rm -rf --one-file-system "$root"
}
trap cleanup EXIT

command -v debootstrap >/dev/null || {
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends debootstrap >/dev/null; }
# The archive this machine's apt reads (deb822 or one-line sources), for debootstrap and the chroot.
mirror=$(awk '/^URIs:/ {print $2; exit} /^deb / {print $2; exit}' /etc/apt/sources.list.d/*.sources /etc/apt/sources.list 2>/dev/null | head -1)
[ -n "$mirror" ] || { echo "first_command_from_bare.sh: no Debian archive in this machine's apt sources" >&2; exit 2; }
t0=$(date +%s.%N)
debootstrap --variant=minbase bookworm "$root" "$mirror" > "$root.debootstrap.log" 2>&1 ||
  { tail -5 "$root.debootstrap.log" >&2; exit 1; }
rm -f "$root.debootstrap.log"
t1=$(date +%s.%N)
git clone -q "$PWD" "$root/root/wlx"
mount --bind /proc "$root/proc" && mounted+=("$root/proc")
mount --bind /dev "$root/dev" && mounted+=("$root/dev")

# The README's first command, as written there (its first line of shell).
command=$(awk '/^```sh/ {getline; print; exit}' README.md)
echo "README's first command: $command"
t2=$(date +%s.%N)
chroot "$root" /bin/bash -c "cd /root/wlx && $command" > "$root/first-command.log" 2>&1 ||
  { tail -20 "$root/first-command.log" >&2; echo "first_command_from_bare.sh: the command failed" >&2; exit 1; }
t3=$(date +%s.%N)
# Idempotent: the same command again installs and compiles nothing.
chroot "$root" /bin/bash -c "cd /root/wlx && $command" > "$root/second-command.log" 2>&1 ||
  { tail -20 "$root/second-command.log" >&2; echo "first_command_from_bare.sh: the second run failed" >&2; exit 1; }
t4=$(date +%s.%N)
awk -v a="$t0" -v b="$t1" -v c="$t2" -v d="$t3" -v e="$t4" -v cores="$(nproc)" 'BEGIN {
  printf "bare Debian 12 (debootstrap minbase): %.0f s\n", b - a
  printf "the README'\''s first command from it, apt included, %d cores: %.0f s (%.1f min)\n", cores, d - c, (d - c) / 60
  printf "the same command again: %.1f s\n", e - d }'
grep -m1 -E "^setup: installing" "$root/first-command.log" | cut -c1-200 || true
tail -2 "$root/first-command.log"
