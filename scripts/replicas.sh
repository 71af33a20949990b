#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# N gridshelld replicas behind haproxy on this machine (docs/deploy.md, "Replicas behind
# haproxy"). No port is chosen here: every replica binds port 0 and reports the ports the kernel
# gave it on its "listening" log line, and the proxy's two ports are bound to port 0 by a small
# launcher that hands the sockets to haproxy (`bind fd@N`). So several sets (tests, other
# people's daemons) can run at once, and no port is handed out before it is bound.
#
#   bash scripts/replicas.sh start 3 [-- GRIDSHELLD-OPTIONS]   # prints the proxy's addresses
#   bash scripts/replicas.sh kill 2        # SIGKILL replica 2 (fault tests)
#   bash scripts/replicas.sh wait-down 2   # until haproxy's checks mark replica 2 down
#   bash scripts/replicas.sh restart 2     # start replica 2 again (new ports, told to haproxy)
#   bash scripts/replicas.sh status
#   bash scripts/replicas.sh stop          # stops haproxy and every replica
#   bash scripts/replicas.sh config G1:H1,G2:H2,... GRPC HTTP   # print a haproxy.cfg
#
# State (ports, pids, logs, the generated haproxy.cfg, haproxy's admin socket) lives in
# GRIDSHELL_REPLICAS_DIR (default /tmp/gridshell-replicas-$USER). GRIDSHELLD names the daemon
# (default build/gridshelld). The proxy listens on 127.0.0.1: gRPC (HTTP/2, cleartext) and the
# HTTP gateway, both routed by the x-gridshell-patch-key header with consistent hashing
# (deploy/haproxy/haproxy.cfg). A restarted replica gets new ports, and haproxy learns them on
# its runtime API (`set server ... addr ... port ...`), as a service registry would tell it.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
STATE="${GRIDSHELL_REPLICAS_DIR:-/tmp/gridshell-replicas-${USER:-$(id -u)}}"
GRIDSHELLD="${GRIDSHELLD:-$ROOT/build/gridshelld}"
TEMPLATE="$ROOT/deploy/haproxy/haproxy.cfg"

log() { echo "replicas: $*" >&2; }

alive() { [ -s "$1" ] && kill -0 "$(cat "$1")" 2>/dev/null; }

healthy() { # healthy PORT: GET /healthz answers 200
  local reply
  { exec 3<>"/dev/tcp/127.0.0.1/$1"; } 2>/dev/null || return 1
  printf 'GET /healthz HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n' >&3
  read -r -t 2 reply <&3 || reply=""
  exec 3<&- 3>&-
  [[ "$reply" == *" 200 "* ]]
}

# admin COMMAND: one command on haproxy's runtime API (its admin socket); the answer on stdout.
admin() {
  python3 - "$STATE/admin.sock" "$1" <<'PY'
import socket, sys
with socket.socket(socket.AF_UNIX) as s:
    s.connect(sys.argv[1])
    s.sendall(sys.argv[2].encode() + b"\n")
    answer = b""
    while chunk := s.recv(65536):
        answer += chunk
sys.stdout.write(answer.decode())
PY
}

# bind_address SPEC: "fd@N" as it is, a bare port as 127.0.0.1:PORT.
bind_address() { [[ "$1" == fd@* ]] && echo "$1" || echo "127.0.0.1:$1"; }

# config SERVERS GRPC HTTP [STATE]: deploy/haproxy/haproxy.cfg with its example server lines
# replaced by one pair per replica (SERVERS: "G1:H1,G2:H2,..." gRPC and HTTP ports) and its
# frontends bound to GRPC and HTTP (ports, or fd@N for sockets haproxy inherits).
config() {
  local servers="$1" grpc state="${4:-/run/gridshell-haproxy}" http i=0 pair lines_g="" lines_h=""
  grpc="$(bind_address "$2")" http="$(bind_address "$3")"
  IFS=',' read -r -a pairs <<<"$servers"
  for pair in "${pairs[@]}"; do
    i=$((i + 1))
    lines_g+="  server r$i 127.0.0.1:${pair%%:*} id $i proto h2 check port ${pair##*:} check-proto h1"$'\n'
    lines_h+="  server r$i 127.0.0.1:${pair##*:} id $i check"$'\n'
  done
  awk -v grpc="$grpc" -v http="$http" -v state="$state" -v g="$lines_g" -v h="$lines_h" '
    /^  server r[0-9]+ .*proto-h2-example/ { if (!done_g++) printf "%s", g; next }
    /^  server r[0-9]+ .*http-example/ { if (!done_h++) printf "%s", h; next }
    { gsub(/127\.0\.0\.1:50050/, grpc); gsub(/127\.0\.0\.1:8079/, http);
      gsub(/\/run\/gridshell-haproxy/, state); print }' "$TEMPLATE"
}

# start_replica I: gridshelld on ports the kernel picks; waits for its "listening" line and keeps
# the two ports in rI.ports. A restarted daemon appends to the killed one's log.
start_replica() {
  local i="$1" offset line k
  offset=$(stat -c %s "$STATE/r$i.log" 2>/dev/null || echo 0)
  "$GRIDSHELLD" --listen 127.0.0.1:0 --http 127.0.0.1:0 "${EXTRA[@]}" >>"$STATE/r$i.log" 2>&1 &
  echo $! >"$STATE/r$i.pid"
  for ((k = 0; k < 600; k++)); do
    line="$(tail -c +$((offset + 1)) "$STATE/r$i.log" | grep -m 1 '"event":"listening"' || true)"
    [ -n "$line" ] && break
    alive "$STATE/r$i.pid" || {
      log "replica $i exited: $(tail -n 3 "$STATE/r$i.log")"
      return 1
    }
    sleep 0.05
  done
  [ -n "$line" ] || {
    log "replica $i did not listen within 30 s"
    return 1
  }
  printf '%s %s\n' "$(sed -E 's/.*"grpc":"[0-9.]+:([0-9]+)".*/\1/' <<<"$line")" \
    "$(sed -E 's/.*"http":"[0-9.]+:([0-9]+)".*/\1/' <<<"$line")" >"$STATE/r$i.ports"
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

# start_proxy SERVERS: binds the proxy's gRPC and HTTP sockets to port 0 on 127.0.0.1, writes
# haproxy.cfg with `bind fd@3` and `bind fd@4`, checks it and starts haproxy (daemonized) with
# the two sockets; their ports go to proxy.ports.
start_proxy() {
  python3 - "$1" "$STATE" "$ROOT/scripts/replicas.sh" <<'PY'
import os, socket, subprocess, sys
servers, state, script = sys.argv[1:4]
ports = []
for fd in (3, 4):  # gRPC, HTTP
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    s.listen(1024)
    ports.append(s.getsockname()[1])
    own = s.detach()
    if own != fd:
        os.dup2(own, fd)  # dup2 leaves the new descriptor inheritable
        os.close(own)
    else:
        os.set_inheritable(fd, True)
with open(os.path.join(state, "proxy.ports"), "w") as out:
    out.write("%d %d\n" % tuple(ports))
config = os.path.join(state, "haproxy.cfg")
with open(config, "w") as out:
    subprocess.run(["bash", script, "config", servers, "fd@3", "fd@4", state], stdout=out,
                   check=True, pass_fds=(3, 4))
subprocess.run(["haproxy", "-c", "-q", "-f", config], check=True, pass_fds=(3, 4))
os.execvp("haproxy", ["haproxy", "-D", "-f", config, "-p", os.path.join(state, "haproxy.pid")])
PY
}

# server_state I: haproxy's view of replica I in both backends, e.g. "UP UP" or "DOWN DOWN".
server_state() {
  admin "show stat" | awk -F, -v s="r$1" '
    $2 == s && $1 == "gridshell_grpc" { g = $18 } $2 == s && $1 == "gridshell_http" { h = $18 }
    END { print g, h }'
}

start() {
  local n="${1:?usage: replicas.sh start N [-- gridshelld options]}" i servers="" grpc http k
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
  for ((i = 1; i <= n; i++)); do start_replica "$i"; done
  for ((i = 1; i <= n; i++)); do
    wait_healthy "$i"
    read -r grpc http <"$STATE/r$i.ports"
    servers+="${servers:+,}$grpc:$http"
  done
  echo "$n" >"$STATE/count"
  start_proxy "$servers"
  read -r grpc http <"$STATE/proxy.ports"
  for ((k = 0; k < 100; k++)); do healthy "$http" && break; sleep 0.1; done
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
  wait-down)
    # haproxy's checks (every 0.5 s, down after 2 failures) notice a dead replica; a bound of
    # 30 s against a proxy that never does.
    for ((k = 0; k < 300; k++)); do
      [ "$(server_state "${2:?replica number}")" = "DOWN DOWN" ] && exit 0
      sleep 0.1
    done
    log "replica $2 is not down in haproxy after 30 s: $(server_state "$2")"
    exit 1
    ;;
  restart)
    i="${2:?replica number}"
    mapfile -t EXTRA <"$STATE/extra"
    [ ${#EXTRA[@]} -eq 1 ] && [ -z "${EXTRA[0]}" ] && EXTRA=()
    stop_pid "$STATE/r$i.pid"
    start_replica "$i"
    wait_healthy "$i"
    read -r grpc http <"$STATE/r$i.ports"
    admin "set server gridshell_grpc/r$i addr 127.0.0.1 port $grpc" >&2
    admin "set server gridshell_grpc/r$i check-port $http" >&2
    admin "set server gridshell_http/r$i addr 127.0.0.1 port $http" >&2
    ;;
  status)
    for f in "$STATE"/r*.pid; do
      [ -e "$f" ] || continue
      i="$(basename "$f" .pid)"
      if alive "$f"; then
        echo "$i running ($(cat "$f"), ports $(cat "$STATE/$i.ports"), haproxy: $(server_state "${i#r}"))"
      else
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
    echo "usage: $0 start N [-- gridshelld options] | stop | kill I | wait-down I | restart I | status | config SERVERS GRPC HTTP" >&2
    exit 2
    ;;
esac
