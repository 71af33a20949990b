#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Starts gridshelld with the web page: builds what is missing first (the C++ daemon, the page),
# then serves the API and the page on loopback and prints the URL. Ctrl-C stops it.
# PORT=8080 by default; extra arguments go to gridshelld (e.g. --token-file FILE).
set -euo pipefail
cd "$(dirname "$0")/.."
PORT="${PORT:-8080}"
if [ ! -x build/gridshelld ]; then
  bash scripts/setup.sh
  bash scripts/build.sh
fi
if [ ! -f client/web/dist/index.html ]; then
  bash scripts/setup-web.sh
  bash scripts/build-web.sh
fi
echo "gridshell: open http://127.0.0.1:${PORT}/" >&2
exec ./build/gridshelld --listen 127.0.0.1:0 --http "127.0.0.1:${PORT}" --static client/web/dist "$@"
