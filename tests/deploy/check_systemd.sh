#!/usr/bin/env bash
# systemd-analyze verify on deploy/systemd's units, with ExecStart pointed at the built
# programs (verify checks that they exist). Any warning fails, and a unit with a misspelt
# key must be refused, or this check proves nothing. Exit 77 = skipped.
#   tests/deploy/check_systemd.sh SOURCE_DIR BIN_DIR
set -euo pipefail
src="$1" bin="$2"
command -v systemd-analyze >/dev/null || { echo "systemd-analyze not installed: skipped"; exit 77; }
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
sed "s|/usr/bin/keel-|$bin/keel-|g" "$src/deploy/systemd/keel-server.service" >"$tmp/keel-server.service"
sed "s|/usr/bin/keel-|$bin/keel-|g" "$src/deploy/systemd/keel-worker@.service" >"$tmp/keel-worker@.service"
cp "$tmp/keel-worker@.service" "$tmp/keel-worker@1.service"  # an instance of the template

verify() { (cd "$tmp" && systemd-analyze verify --man=no "$@" 2>&1); }
out="$(verify keel-server.service keel-worker@1.service)" || { echo "$out"; exit 1; }
if [ -n "$out" ]; then echo "$out"; echo "systemd-analyze verify warned"; exit 1; fi
echo "keel-server.service, keel-worker@.service: verified"

sed 's/^Restart=/Restrat=/' "$tmp/keel-server.service" >"$tmp/broken.service"
out="$(verify broken.service)" || true
if [ -z "$out" ]; then echo "a unit with a misspelt key passed verify"; exit 1; fi
echo "a misspelt key is refused: $out"
