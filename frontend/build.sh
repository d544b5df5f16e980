#!/usr/bin/env bash
# Rebuild graphvision/studio/static from frontend/ (pinned by package-lock.json).
set -euo pipefail
cd "$(dirname "$0")"
npm ci --no-audit --no-fund
node --test test/
node build.mjs
