#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Installs what gridshell's build needs from Debian 12 packages (group "build" of
# scripts/packages.txt). Idempotent: installs only what is missing.
set -euo pipefail
bash "$(dirname "$0")/install-packages.sh" build
