#!/usr/bin/env bash
# Serves the built page (web/dist/, made by web/build.sh) on http://127.0.0.1:PORT/ (default
# 8080). Any static file server does; this one is Python's.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
port="${1:-8080}"
[[ -f "$here/dist/index.html" ]] || { echo "web/serve.sh: no page yet: run web/build.sh first" >&2; exit 1; }
echo "serving the page on http://127.0.0.1:$port/ (Ctrl-C stops)" >&2
exec python3 -m http.server "$port" --bind 127.0.0.1 --directory "$here/dist"
