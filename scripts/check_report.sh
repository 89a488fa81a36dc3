#!/usr/bin/env bash
# Loads an `impulse analyze --report` page in headless Chromium and checks that it renders:
# the page loads, its inlined Vega draws every plot (<body data-ready="1">, no data-error), the
# dumped DOM holds as many Vega <svg> plots as the page declares (<meta name="impulse-plots"
# content="N">), and the browser log has no console errors.
# Writes a screenshot beside the report (REPORT.png) to look at.
#
#   scripts/check_report.sh REPORT.html [SCREENSHOT.png]
#
# Installs Debian's `chromium` when it is missing (needs root or sudo). Not part of the test
# suite (tests/web/test_analyze_report.py is: marks, log axes, hover, zoom); this is the quick
# look at a report of your own.
set -euo pipefail

if [ $# -lt 1 ] || [ $# -gt 2 ]; then
    echo "usage: $0 REPORT.html [SCREENSHOT.png]" >&2
    exit 2
fi
report=$1
[ -f "$report" ] || { echo "error: $report: no such file" >&2; exit 2; }
report_abs=$(cd "$(dirname "$report")" && pwd)/$(basename "$report")
shot=${2:-${report_abs%.html}.png}

browser=""
for b in chromium chromium-browser; do
    if command -v "$b" > /dev/null 2>&1; then browser=$b; break; fi
done
if [ -z "$browser" ]; then
    echo "installing chromium (Debian package) ..." >&2
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends chromium >&2
    browser=chromium
fi

expected=$(grep -o '<meta name="impulse-plots" content="[0-9]*"' "$report" | grep -o '[0-9]*' | head -1 || true)
if [ -z "$expected" ]; then
    echo "FAIL: $report has no <meta name=\"impulse-plots\"> (not an impulse report?)" >&2
    exit 1
fi

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
flags=(--headless --no-sandbox --disable-gpu --disable-background-networking
       --disable-component-update --disable-sync --no-first-run --enable-logging=stderr --v=0
       --hide-scrollbars --virtual-time-budget=10000)

# Each run gets its own throw-away profile; a timeout guards against a hung browser.
status=0
timeout 120 "$browser" "${flags[@]}" --user-data-dir="$(mktemp -d -p "$work")" \
    --dump-dom "file://$report_abs" > "$work/dom.html" 2> "$work/dom.log" || status=$?
if [ $status -ne 0 ] || [ ! -s "$work/dom.html" ]; then
    echo "FAIL: $browser could not load $report (exit $status)" >&2
    tail -20 "$work/dom.log" >&2
    exit 1
fi
status=0
timeout 120 "$browser" "${flags[@]}" --user-data-dir="$(mktemp -d -p "$work")" \
    --window-size=1440,2600 --screenshot="$shot" "file://$report_abs" \
    > /dev/null 2> "$work/shot.log" || status=$?
if [ $status -ne 0 ] || [ ! -s "$shot" ]; then
    echo "FAIL: $browser could not take a screenshot of $report (exit $status)" >&2
    tail -20 "$work/shot.log" >&2
    exit 1
fi

fail=0
grep -q '</html>' "$work/dom.html" || { echo "FAIL: the dumped DOM is incomplete" >&2; fail=1; }
# One line, so the <body ...> tag and each Vega <svg class="marks" ...> are matched whole.
tr '\n' ' ' < "$work/dom.html" > "$work/dom.line"
body=$(grep -o '<body[^>]*>' "$work/dom.line" | head -1 || true)
case "$body" in
    *'data-ready="1"'*) ;;
    *) echo "FAIL: the plots were not drawn: $body" >&2; fail=1 ;;
esac
svgs=$( (grep -o '<svg [^>]*class="marks"' "$work/dom.line" || true) | wc -l)
if [ "$svgs" -ne "$expected" ]; then
    echo "FAIL: $svgs Vega <svg> plots in the DOM, the report declares $expected plots" >&2
    fail=1
fi
errors=$(cat "$work/dom.log" "$work/shot.log" | grep -E 'Uncaught|ERROR:CONSOLE|CONSOLE\(' || true)
if [ -n "$errors" ]; then
    echo "FAIL: console errors while loading $report:" >&2
    echo "$errors" >&2
    fail=1
fi
if [ $fail -ne 0 ]; then exit 1; fi
echo "ok: $report loads in $($browser --version 2>/dev/null | head -1); $svgs/$expected plots drawn; no console errors; screenshot $shot"
