# Sourced by the benchmark scripts: their arguments [SYLVA_EXE [DIR]]. Sets root (the
# source tree), exe (default build/server/sylva) and tmp: DIR, created if need be
# and kept, or a temporary folder removed at exit.
root=$(cd "$(dirname "$0")/../.." && pwd)
exe=${1:-"$root/build/server/sylva"}
if [ $# -ge 2 ]; then
  tmp=$2
  mkdir -p "$tmp"
else
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' EXIT
fi
