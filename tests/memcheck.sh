#!/bin/sh
# Runs a command under valgrind and passes only when it exits with the expected
# status and valgrind reported nothing (valgrind's own errors exit 99).
# Usage: memcheck.sh EXPECTED_STATUS COMMAND [ARGS...]
# valgrind.supp holds the blocks libraries keep by design until the process ends.
expected=$1
shift
valgrind --error-exitcode=99 --leak-check=full --errors-for-leak-kinds=all -q \
  --suppressions="$(dirname "$0")/valgrind.supp" "$@" >/dev/null
status=$?
if [ "$status" -ne "$expected" ]; then
  echo "memcheck: exit status $status, expected $expected (99: valgrind found errors)" >&2
  echo "0 passed, 1 failed"
  exit 1
fi
echo "1 passed, 0 failed"
