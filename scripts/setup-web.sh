#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Installs what the web page (client/web) and its browser tests need: Debian's Chromium when
# missing (group "web" of scripts/packages.txt), then the page's npm packages exactly as
# package-lock.json pins them. Idempotent: `npm ci` runs only when the lock file changed since
# the last install.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-packages.sh web
# Vite 7 needs Node.js 20.19 or newer: the machine's own (Debian 12's nodejs package is 18, too
# old, so it is not installed from there).
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  echo "setup-web: Node.js >= 20.19 with npm is needed (Debian 12's nodejs 18 is too old)" >&2
  exit 1
fi
node -e 'const [a,b]=process.versions.node.split(".").map(Number); if (a<20||(a===20&&b<19)) { console.error("setup-web: Node.js "+process.versions.node+" is too old for Vite 7 (need >= 20.19)"); process.exit(1); }'
cd client/web
stamp=node_modules/.gridshell-lock.sha256
want="$(sha256sum package-lock.json | cut -d' ' -f1)"
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
  npm ci --no-audit --no-fund --loglevel=error >&2
  echo "$want" > "$stamp"
fi
