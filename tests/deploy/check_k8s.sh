#!/usr/bin/env bash
# deploy/k8s against the Kubernetes and KEDA schemas (validate_k8s.mjs). Exit 77 = skipped.
#   tests/deploy/check_k8s.sh SOURCE_DIR
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
command -v node >/dev/null || { echo "node not installed: skipped"; exit 77; }
[ -d "$here/node_modules/kubernetes-models" ] ||
  { echo "tests/deploy/node_modules missing (bash deploy/setup.sh runs npm ci there): skipped"; exit 77; }
cd "$here" && exec node validate_k8s.mjs "$1/deploy/k8s"
