# Sourced by the browser tests: sets chromium (Debian's /usr/bin/chromium) and
# returns 1 with one FAIL line when node, Chromium or the npm packages are
# missing. Not a skip: without them a browser test fails.
#   source require_browser.sh SOURCE_DIR || exit 1
chromium=/usr/bin/chromium
require_browser_missing=
command -v node >/dev/null 2>&1 || require_browser_missing="node"
[ -x "$chromium" ] || require_browser_missing="$require_browser_missing $chromium"
[ -f "$1/node_modules/puppeteer-core/package.json" ] ||
  require_browser_missing="$require_browser_missing $1/node_modules/puppeteer-core"
if [ -n "$require_browser_missing" ]; then
  echo "FAIL: ${require_browser_missing# } missing: run scripts/install-deps.sh"
  return 1
fi
