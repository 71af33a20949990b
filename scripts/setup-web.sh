#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Installs what the web page (client/web) and its browser tests need: Node.js and npm, and
# Debian's Chromium, from Debian packages when missing (root, as on CI; sudo otherwise), then the
# page's npm packages exactly as package-lock.json pins them. Idempotent: `npm ci` runs only
# when the lock file changed since the last install.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-packages.sh web  # Chromium
missing=()
command -v node >/dev/null 2>&1 || missing+=(nodejs)
command -v npm >/dev/null 2>&1 || missing+=(npm)
if [ ${#missing[@]} -gt 0 ]; then  # the machine's own Node.js when it has one (see below)
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  echo "setup-web: installing ${missing[*]}" >&2
  $SUDO apt-get -o DPkg::Lock::Timeout=1800 update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get -o DPkg::Lock::Timeout=1800 install -y -qq \
    --no-install-recommends "${missing[@]}" >&2
fi
# Vite 7 needs Node.js 20.19 or newer (the machine's Node.js; Debian 12's own nodejs is 18).
node -e 'const [a,b]=process.versions.node.split(".").map(Number); if (a<20||(a===20&&b<19)) { console.error("setup-web: Node.js "+process.versions.node+" is too old for Vite 7 (need >= 20.19)"); process.exit(1); }'
cd client/web
stamp=node_modules/.gridshell-lock.sha256
want="$(sha256sum package-lock.json | cut -d' ' -f1)"
if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$want" ]; then
  npm ci --no-audit --no-fund --loglevel=error >&2
  echo "$want" > "$stamp"
fi
