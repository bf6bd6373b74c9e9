#!/usr/bin/env bash
# puppeteer-core, pinned by tests/review/package-lock.json, for the browser test of
# `gait review` (tests/review.rs drives Debian's Chromium over the DevTools protocol with it).
# Installed under target/ so a fresh machine gets it and later runs are offline.
# Prints the node_modules folder to give the test as NODE_PATH.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
dest="$root/target/gait-deps/review-node"
if ! command -v npm >/dev/null; then
  echo "setup: installing Debian packages: nodejs npm" >&2
  sudo_cmd=""
  [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends nodejs npm >/dev/null
fi
if [ ! -f "$dest/node_modules/puppeteer-core/package.json" ] \
  || ! cmp -s "$root/tests/review/package-lock.json" "$dest/package-lock.json"; then
  echo "setup: installing puppeteer-core for the review browser test (npm)" >&2
  mkdir -p "$dest"
  cp "$root/tests/review/package.json" "$root/tests/review/package-lock.json" "$dest/"
  (cd "$dest" && npm ci --ignore-scripts --no-audit --no-fund --loglevel=error >&2)
fi
echo "$dest/node_modules"
