# Debian's headless Chromium for the browser tests (sourced after appliance.sh, which sets $tmp):
# a fresh profile each run, bounded by `timeout` (BROWSER_TIMEOUT_S, default 60), its stderr (noise)
# in "$tmp/chromium.log"; body_attr reads one <body data-*> attribute from a dumped DOM on stdin.
browser() {
  local profile
  profile=$(mktemp -d "$tmp/chromium.XXXXXX")
  timeout "${BROWSER_TIMEOUT_S:-60}" chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
    --disable-background-networking --disable-component-update --disable-sync --hide-scrollbars \
    --user-data-dir="$profile" "$@" 2>>"$tmp/chromium.log"
}
body_attr() { grep -o "<body[^>]*>" | grep -o "$1=\"[^\"]*\"" | head -1 | cut -d'"' -f2; }
