#!/usr/bin/env bash
# Re-vendor the browser libraries from npm (pinned versions; see README.md). Run from anywhere; needs npm.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
npm pack --silent echarts@6.1.0 swagger-ui-dist@5.35.0 redoc@2.5.4 >/dev/null
for t in *.tgz; do mkdir "${t%.tgz}"; tar xzf "$t" -C "${t%.tgz}"; done

e="$here/echarts-6.1.0"; mkdir -p "$e/licenses"
cp echarts-6.1.0/package/dist/echarts.esm.min.mjs "$e/echarts.esm.min.js"
cp echarts-6.1.0/package/{LICENSE,NOTICE} "$e/"; cp echarts-6.1.0/package/licenses/* "$e/licenses/"

s="$here/swagger-ui-dist-5.35.0"; mkdir -p "$s"
cp swagger-ui-dist-5.35.0/package/{swagger-ui-bundle.js,swagger-ui-bundle.js.LICENSE.txt,swagger-ui.css,favicon-32x32.png,LICENSE,NOTICE} "$s/"

r="$here/redoc-2.5.4"; mkdir -p "$r"
cp redoc-2.5.4/package/bundles/{redoc.standalone.js,redoc.standalone.js.LICENSE.txt} redoc-2.5.4/package/LICENSE "$r/"
# The one change to a vendored file: ReDoc's sidebar loads its logo from cdn.redoc.ly, the only request
# it makes outside the service. Point it at an empty inline SVG (the "API docs by Redocly" link stays).
sed -i 's#https://cdn.redoc.ly/redoc/logo-mini.svg#data:image/svg+xml,%3Csvg xmlns=%22http://www.w3.org/2000/svg%22/%3E#' "$r/redoc.standalone.js"
! grep -q "cdn.redoc.ly" "$r/redoc.standalone.js"
(cd "$here" && sha256sum */*.js */*.css)
