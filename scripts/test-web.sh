#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# The web page's tests: unit tests of its pure code, then end-to-end tests in headless Debian
# Chromium (playwright-core) against a real gridshelld on a free loopback port, started and
# stopped by the tests. Needs scripts/setup-web.sh, scripts/build-web.sh and the C++ build
# (./build/gridshelld, or GRIDSHELLD=path).
set -euo pipefail
cd "$(dirname "$0")/.."
node --test --test-reporter=spec tests/web/unit.test.mjs
node --test --test-reporter=spec --test-timeout=240000 tests/web/e2e.test.mjs
