#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Type-checks and bundles the web page into client/web/dist (served by gridshelld at /).
# Run scripts/setup-web.sh first.
set -euo pipefail
cd "$(dirname "$0")/../client/web"
npx --no-install tsc --noEmit
npx --no-install vite build --logLevel warn
echo "build-web: $(du -sh dist | cut -f1) in client/web/dist; gzipped JS+CSS: $(cat dist/assets/*.js dist/assets/*.css | gzip -9 | wc -c) bytes" >&2
