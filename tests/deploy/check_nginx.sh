#!/usr/bin/env bash
# nginx -t on deploy/nginx/keel.conf inside a minimal http {} block, in a private prefix.
# A broken copy must be refused, or this check proves nothing. Exit 77 = skipped.
#   tests/deploy/check_nginx.sh SOURCE_DIR
set -euo pipefail
src="$1"
nginx="$(command -v nginx || echo /usr/sbin/nginx)"
[ -x "$nginx" ] || { echo "nginx not installed: skipped"; exit 77; }
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/logs"
main() {
  cat <<CONF
pid $tmp/nginx.pid;
error_log $tmp/logs/error.log;
events {}
http {
  access_log off;
  client_body_temp_path $tmp/body;
  proxy_temp_path $tmp/proxy;
  include $1;
}
CONF
}
main "$src/deploy/nginx/keel.conf" >"$tmp/nginx.conf"
"$nginx" -t -q -p "$tmp" -c "$tmp/nginx.conf"
echo "deploy/nginx/keel.conf: nginx -t passed"
sed 's/proxy_read_timeout 120s;/proxy_read_timeout 120s/' "$src/deploy/nginx/keel.conf" >"$tmp/broken.conf"
main "$tmp/broken.conf" >"$tmp/broken-nginx.conf"
if "$nginx" -t -q -p "$tmp" -c "$tmp/broken-nginx.conf" 2>/dev/null; then
  echo "a broken copy passed nginx -t"; exit 1
fi
echo "a broken copy is refused"
