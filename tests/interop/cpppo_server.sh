#!/usr/bin/env bash
# Run cpppo's EtherNet/IP server simulator in the foreground, on loopback only.
#
#   tests/interop/cpppo_server.sh [--port N] [--address A] [--lifetime S] [--no-default-tags]
#                                 [-v] [CPPPO_ARG_OR_TAG...]
#
# It exec's (via coreutils `timeout`, which forwards SIGTERM/SIGINT to the server), so the PID
# a test spawns is the one to kill. Readiness: poll until the TCP port accepts (the first stdout
# line, "Network TCP Server address = ('127.0.0.1', N)", is printed just before it listens).
# Never runs longer than --lifetime seconds (default 600).
#
# Default tags (attributes the clients can get/set), placed like NORD parameters (class 100 =
# the module's parameters, 101 = FI 1's; attribute = parameter number). cpppo cannot put a tag
# on instance 0, so these use instance 1:
#   P102@0x64/1/102=INT  P717@0x64/1/717=INT (16-bit attribute id)  P1000@0x64/1/1000=DINT
#   FI1_P102@0x65/1/102=INT
# --no-default-tags drops them; extra positional arguments are passed to cpppo verbatim
# (more tags like Name@0x66/2/3=INT, Name=INT[10], or cpppo options like --delay 2).
set -euo pipefail

# The venv .ci/interop-setup makes in the build folder, unless INTEROP_VENV names another.
ROOT="$(cd "$(dirname "$0")/../.." && pwd)"
VENV="${INTEROP_VENV:-${CARGO_TARGET_DIR:-$ROOT/target}/interop-venv}"
PY="${INTEROP_PYTHON:-$VENV/bin/python}"
PORT=44818
ADDR=127.0.0.1
LIFETIME=600
DEFAULT_TAGS=(P102@0x64/1/102=INT P717@0x64/1/717=INT P1000@0x64/1/1000=DINT FI1_P102@0x65/1/102=INT)
USE_DEFAULT_TAGS=1
VERBOSE=()
EXTRA=()

usage() { sed -n '2,20p' "$0" | sed 's/^# \{0,1\}//'; }

while [ $# -gt 0 ]; do
  case "$1" in
    --port) PORT="${2:?--port needs a value}"; shift 2 ;;
    --port=*) PORT="${1#*=}"; shift ;;
    --address) ADDR="${2:?--address needs a value}"; shift 2 ;;
    --address=*) ADDR="${1#*=}"; shift ;;
    --lifetime) LIFETIME="${2:?--lifetime needs a value}"; shift 2 ;;
    --lifetime=*) LIFETIME="${1#*=}"; shift ;;
    --no-default-tags) USE_DEFAULT_TAGS=0; shift ;;
    -v|--verbose) VERBOSE+=(-v); shift ;;
    -h|--help) usage; exit 0 ;;
    --) shift; EXTRA+=("$@"); break ;;
    *) EXTRA+=("$1"); shift ;;
  esac
done

case "$ADDR" in
  127.*|localhost) ;;
  *) echo "cpppo_server.sh: refusing to bind $ADDR (loopback only)" >&2; exit 2 ;;
esac
if ! [[ "$PORT" =~ ^[0-9]+$ ]] || [ "$PORT" -lt 1 ] || [ "$PORT" -gt 65535 ]; then
  echo "cpppo_server.sh: bad port $PORT" >&2; exit 2
fi
if [ ! -x "$PY" ] || ! "$PY" -c 'import cpppo.server.enip' 2>/dev/null; then
  echo "cpppo_server.sh: cpppo not importable with $PY; run .ci/interop-setup first" >&2
  exit 3
fi

TAGS=()
if [ "$USE_DEFAULT_TAGS" = 1 ]; then TAGS=("${DEFAULT_TAGS[@]}"); fi

# -S: a simple, non-routing device (like a NORD bus interface): requests must carry no route
#     path (no Unconnected_Send wrapper), exactly what both client scripts send.
# -A: print the bound address on stdout (readiness hint). --no-config: ignore any cpppo.cfg in
#     the cwd, ~ or /etc, so every run gets cpppo's built-in identity (a 1756-L61 "LOGIX5561").
export PYTHONUNBUFFERED=1
exec timeout --signal=TERM --kill-after=5 "$LIFETIME" \
  "$PY" -m cpppo.server.enip --address "$ADDR:$PORT" --no-config -S -A \
  ${VERBOSE[@]+"${VERBOSE[@]}"} ${TAGS[@]+"${TAGS[@]}"} ${EXTRA[@]+"${EXTRA[@]}"}
