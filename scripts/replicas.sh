#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# N gridshelld replicas behind haproxy on this machine (docs/deploy.md, "Replicas behind
# haproxy"): every port is a free loopback port, so that several sets (tests, other people's
# daemons) can run at once.
#
#   bash scripts/replicas.sh start 3 [-- GRIDSHELLD-OPTIONS]   # prints the proxy's addresses
#   bash scripts/replicas.sh kill 2        # SIGKILL replica 2 (fault tests)
#   bash scripts/replicas.sh restart 2     # start replica 2 again on its ports
#   bash scripts/replicas.sh status
#   bash scripts/replicas.sh stop          # stops haproxy and every replica
#   bash scripts/replicas.sh config G1:H1,G2:H2,... GRPC HTTP   # print a haproxy.cfg
#
# State (ports, pids, logs, the generated haproxy.cfg) lives in GRIDSHELL_REPLICAS_DIR (default
# /tmp/gridshell-replicas-$USER). GRIDSHELLD names the daemon (default build/gridshelld). The
# proxy listens on 127.0.0.1: gRPC (HTTP/2, cleartext) and the HTTP gateway, both routed by the
# x-gridshell-patch-key header with consistent hashing (deploy/haproxy/haproxy.cfg).
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
STATE="${GRIDSHELL_REPLICAS_DIR:-/tmp/gridshell-replicas-${USER:-$(id -u)}}"
GRIDSHELLD="${GRIDSHELLD:-$ROOT/build/gridshelld}"
TEMPLATE="$ROOT/deploy/haproxy/haproxy.cfg"

log() { echo "replicas: $*" >&2; }

free_port() {
  python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

alive() { [ -s "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null; }

healthy() { # healthy PORT: GET /healthz answers 200
  local reply
  { exec 3<>"/dev/tcp/127.0.0.1/$1"; } 2>/dev/null || return 1
  printf 'GET /healthz HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n' >&3
  read -r -t 2 reply <&3 || reply=""
  exec 3<&- 3>&-
  [[ "$reply" == *" 200 "* ]]
}

# config SERVERS GRPC_PORT HTTP_PORT [STATE]: deploy/haproxy/haproxy.cfg with its example server
# lines replaced by one pair per replica (SERVERS: "G1:H1,G2:H2,..." gRPC and HTTP ports).
config() {
  local servers="$1" grpc="$2" http="$3" state="${4:-/run/gridshell-haproxy}" i=0 pair lines_g="" lines_h=""
  IFS=',' read -r -a pairs <<<"$servers"
  for pair in "${pairs[@]}"; do
    i=$((i + 1))
    lines_g+="  server r$i 127.0.0.1:${pair%%:*} id $i proto h2 check port ${pair##*:} check-proto h1"$'\n'
    lines_h+="  server r$i 127.0.0.1:${pair##*:} id $i check"$'\n'
  done
  awk -v grpc="$grpc" -v http="$http" -v state="$state" -v g="$lines_g" -v h="$lines_h" '
    /^  server r[0-9]+ .*proto-h2-example/ { if (!done_g++) printf "%s", g; next }
    /^  server r[0-9]+ .*http-example/ { if (!done_h++) printf "%s", h; next }
    { gsub(/127\.0\.0\.1:50050/, "127.0.0.1:" grpc); gsub(/127\.0\.0\.1:8079/, "127.0.0.1:" http);
      gsub(/\/run\/gridshell-haproxy/, state); print }' "$TEMPLATE"
}

start_replica() { # start_replica I
  local i="$1" grpc http
  read -r grpc http <"$STATE/r$i.ports"
  # Appends: a restarted replica's log follows the killed one's.
  "$GRIDSHELLD" --listen "127.0.0.1:$grpc" --http "127.0.0.1:$http" \
    "${EXTRA[@]}" >>"$STATE/r$i.log" 2>&1 &
  echo $! >"$STATE/r$i.pid"
}

wait_healthy() { # wait_healthy I
  local i="$1" grpc http k
  read -r grpc http <"$STATE/r$i.ports"
  for ((k = 0; k < 300; k++)); do
    healthy "$http" && return 0
    alive "$STATE/r$i.pid" || {
      log "replica $i exited: $(tail -n 3 "$STATE/r$i.log")"
      return 1
    }
    sleep 0.1
  done
  log "replica $i is not healthy after 30 s"
  return 1
}

start() {
  local n="${1:?usage: replicas.sh start N [-- gridshelld options]}" i servers="" grpc http
  shift
  [ "${1:-}" = "--" ] && shift
  EXTRA=("$@")
  [ -x "$GRIDSHELLD" ] || { log "no daemon at $GRIDSHELLD (bash scripts/build.sh)"; exit 1; }
  command -v haproxy >/dev/null || { log "haproxy is not installed (bash scripts/setup.sh)"; exit 1; }
  if alive "$STATE/haproxy.pid"; then
    log "already running in $STATE (stop first)"
    cat "$STATE/env"
    return 0
  fi
  mkdir -p "$STATE"
  printf '%s\n' "${EXTRA[@]}" >"$STATE/extra"
  for ((i = 1; i <= n; i++)); do
    echo "$(free_port) $(free_port)" >"$STATE/r$i.ports"
    start_replica "$i"
  done
  for ((i = 1; i <= n; i++)); do
    wait_healthy "$i"
    read -r grpc http <"$STATE/r$i.ports"
    servers+="${servers:+,}$grpc:$http"
  done
  echo "$n" >"$STATE/count"
  grpc="$(free_port)" http="$(free_port)"
  config "$servers" "$grpc" "$http" "$STATE" >"$STATE/haproxy.cfg"
  haproxy -c -q -f "$STATE/haproxy.cfg"
  haproxy -D -f "$STATE/haproxy.cfg" -p "$STATE/haproxy.pid"
  for ((i = 0; i < 100; i++)); do healthy "$http" && break; sleep 0.1; done
  printf 'GRIDSHELL_PROXY_GRPC=127.0.0.1:%s\nGRIDSHELL_PROXY_HTTP=127.0.0.1:%s\n' "$grpc" "$http" \
    >"$STATE/env"
  log "$n replicas behind haproxy: gRPC 127.0.0.1:$grpc, HTTP http://127.0.0.1:$http/ ($STATE)"
  cat "$STATE/env"
}

stop_pid() { # stop_pid PIDFILE
  local pid k
  alive "$1" || return 0
  pid="$(cat "$1")"
  kill "$pid" 2>/dev/null || true
  for ((k = 0; k < 150; k++)); do
    kill -0 "$pid" 2>/dev/null || return 0
    sleep 0.1
  done
  kill -KILL "$pid" 2>/dev/null || true
}

stop() {
  [ -d "$STATE" ] || return 0
  local f
  stop_pid "$STATE/haproxy.pid"
  for f in "$STATE"/r*.pid; do [ -e "$f" ] && stop_pid "$f"; done
  rm -rf "$STATE"
  log "stopped"
}

case "${1:-}" in
  start)
    shift
    start "$@"
    ;;
  stop) stop ;;
  kill)
    kill -KILL "$(cat "$STATE/r${2:?replica number}.pid")"
    ;;
  restart)
    mapfile -t EXTRA <"$STATE/extra"
    [ ${#EXTRA[@]} -eq 1 ] && [ -z "${EXTRA[0]}" ] && EXTRA=()
    stop_pid "$STATE/r${2:?replica number}.pid"
    start_replica "$2"
    wait_healthy "$2"
    ;;
  status)
    for f in "$STATE"/r*.pid; do
      [ -e "$f" ] || continue
      i="$(basename "$f" .pid)"
      if alive "$f"; then echo "$i running ($(cat "$f"), ports $(cat "$STATE/$i.ports"))"; else
        echo "$i stopped"
      fi
    done
    if alive "$STATE/haproxy.pid"; then cat "$STATE/env"; else echo "haproxy stopped"; fi
    ;;
  config)
    shift
    config "$@"
    ;;
  *)
    echo "usage: $0 start N [-- gridshelld options] | stop | kill I | restart I | status | config SERVERS GRPC HTTP" >&2
    exit 2
    ;;
esac
