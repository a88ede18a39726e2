#!/usr/bin/env bash
# chromium_test.sh — the demo page and our SVG previews in a real browser: headless Chromium
# renders them and must draw them without a console error.
#   chromium_test.sh BUILD_DIR SOURCE_DIR [SHARED_DIR]
#
# 1. Builds demo.db and demo.html as `./run.sh demo` does (sql/schema.sql, synth_corpus.sql,
#    the real corpus through import_bvh.sql when SHARED_DIR/corpora/bandai-namco-1/data exists,
#    then sql/demo.sql), plus standalone documents: an animated motion_svg, an affect_heatmap,
#    an animated motion_svg_group in the top view and a strip labelled by state, each written to
#    its own .svg file, parsed first by Python's XML parser (well-formedness); a standalone SVG
#    is parsed as XML by the browser too, so an error shows up in its DOM as a <parsererror>.
# 2. Checks that the console capture works: a canary page with a bad SVG attribute and a
#    script error must produce both console lines (else the test itself is broken).
# 3. For each document: `chromium --headless --enable-logging=stderr --v=0 --dump-dom` and
#    `--screenshot`; no line "INFO:CONSOLE" in Chromium's log (SVG attribute errors, such as
#    "Error: <path> attribute d: Expected number", are logged there as console errors), no
#    <parsererror> in the DOM, and a screenshot that is not blank: at least 16 distinct
#    colours and 1 % of pixels that are not near-white (tests/client/png_stats.py: the PNG
#    decoded with zlib, no imaging library).
# 4. SMIL: the demo's DOM holds <animate> elements (figures, time bars) and animateTransform
#    (trajectories); the standalone animation's screenshots after 0.3 s and 1.3 s of virtual
#    time differ (the figure moves).
# Exits 77 (CTest's skip) when chromium is not installed (`./run.sh test` installs it).
set -uo pipefail
build=$(cd "$1" && pwd) src=$(cd "$2" && pwd) shared=${3:-}
here=$(cd "$(dirname "$0")" && pwd)

browser=$(command -v chromium || command -v chromium-browser || true)
if [ -z "$browser" ]; then
    echo "SKIP: chromium not installed (apt-get install chromium; ./run.sh test installs it)"
    exit 77
fi
shell=$(command -v sqlite3) || { echo "FAIL: no sqlite3 shell"; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1
passed=0 failed=0
ok() { echo "ok: $*"; passed=$((passed + 1)); }
bad() { echo "FAIL: $*"; failed=$((failed + 1)); }
finish() { echo "chromium: $passed passed, $failed failed"; [ "$failed" -eq 0 ]; exit $?; }

# Chromium refuses to run as root without --no-sandbox (and a CI container has no user
# namespaces for its sandbox); its own profile directory keeps it off the user's.
flags=(--headless --disable-gpu --no-first-run --hide-scrollbars --mute-audio
       --user-data-dir="$work/profile" --enable-logging=stderr --v=0)
[ "$(id -u)" -eq 0 ] && flags+=(--no-sandbox)
# chrome FILE OUT_PREFIX [extra flags…]: the DOM into OUT.dom, the log into OUT.log
chrome() {
    local file=$1 out=$2
    shift 2
    timeout 120 "$browser" "${flags[@]}" "$@" --dump-dom "file://$work/$file" \
        >"$out.dom" 2>"$out.log"
}
shot() { # shot FILE OUT.png WIDTH,HEIGHT [extra flags…]
    local file=$1 png=$2 size=$3
    shift 3
    timeout 120 "$browser" "${flags[@]}" "$@" --window-size="$size" --screenshot="$work/$png" \
        "file://$work/$file" >/dev/null 2>"$png.log"
}

# 1. the documents
q() { "$shell" -bail demo.db -cmd ".load $build/affect" "$@"; }
"$shell" demo.db < "$src/sql/schema.sql" || { bad "sql/schema.sql"; finish; }
q < "$src/sql/synth_corpus.sql" >/dev/null || { bad "sql/synth_corpus.sql"; finish; }
corpus=$shared/corpora/bandai-namco-1/data
if [ -n "$shared" ] && [ -d "$corpus" ]; then
    q -cmd ".parameter set :dir '$corpus'" -cmd ".parameter set :unit cm" \
        -cmd ".parameter set :source bandai-namco-1" < "$src/sql/import_bvh.sql" >/dev/null ||
        { bad "sql/import_bvh.sql"; finish; }
else
    echo "SKIP: no corpus at $corpus: the demo page is built from the synthetic corpus only"
fi
start=$(date +%s)
if ! OPENBLAS_NUM_THREADS=1 q < "$src/sql/demo.sql" > summary.txt 2>&1; then
    bad "sql/demo.sql: $(tail -3 summary.txt)"
    finish
fi
echo "  (demo.sql: $(($(date +%s) - start)) s, demo.html: $(wc -c < demo.html) bytes)"
q "SELECT writefile('anim.svg', motion_svg(motion_synth('wave', 'happy', 1),
                                '{\"animate\":true,\"view\":\"side\",\"title\":\"wave\"}'));
   SELECT writefile('heat.svg', affect_heatmap(r.value, c.value, r.key * 3 + c.key,
                                '{\"title\":\"a <b> & c\",\"x_label\":\"joint\"}'))
     FROM json_each('[\"sad · state 1\",\"sad · state 2\"]') AS r,
          json_each('[\"Hand_L\",\"Head\",\"Foot_R\"]') AS c;
   SELECT writefile('group.svg', motion_svg_group(m, c, '{\"animate\":true,\"view\":\"top\"}'))
     FROM (SELECT motion_synth('walk', e.value, 1) AS m, e.value AS c
             FROM json_each('[\"sad\",\"angry\"]') AS e);
   SELECT writefile('states.svg', motion_svg(motion_synth('bow', 'sad', 1),
                                  '{\"labels\":\"state\",\"frames\":4}'));" >/dev/null ||
    { bad "writing the standalone SVG documents"; finish; }
# each standalone document is well-formed XML (Python's parser, before any browser)
for f in anim.svg heat.svg group.svg states.svg; do
    if err=$(python3 -c 'import sys, xml.etree.ElementTree as E; E.parse(sys.argv[1])' "$f" 2>&1)
    then ok "$f: well-formed XML"; else bad "$f: not well-formed XML: $err"; fi
done

# 2. the canary: the console capture must see an SVG attribute error and a script error
cat > canary.html <<'EOF'
<!doctype html><html><body><svg xmlns="http://www.w3.org/2000/svg" width="40" height="40">
<path d="M0 0L10 zz" stroke="red"/></svg><script>nosuch();</script></body></html>
EOF
chrome canary.html canary
if grep -q 'INFO:CONSOLE.*attribute d' canary.log && grep -q 'INFO:CONSOLE.*Uncaught' canary.log; then
    ok "the console capture sees a canary page's SVG and script errors"
else
    bad "the console capture missed the canary's errors; Chromium's log:"
    sed 's/^/    /' canary.log | tail -20
    finish
fi

# 3. each document: no console error, no XML parse error, a screenshot that is not blank
check_doc() { # check_doc FILE WIDTH,HEIGHT
    local file=$1 size=$2 name=${1%.*}
    chrome "$file" "$name"
    if grep -q 'INFO:CONSOLE' "$name.log"; then
        bad "$file: console messages:"
        grep 'INFO:CONSOLE' "$name.log" | head -10 | sed 's/^/    /'
    else
        ok "$file: no console message"
    fi
    if [ ! -s "$name.dom" ]; then
        bad "$file: empty DOM"
    elif grep -qi 'parsererror' "$name.dom"; then
        bad "$file: the document does not parse: $(grep -io 'parsererror.\{0,200\}' "$name.dom" | head -2)"
    else
        ok "$file: parsed ($(wc -c < "$name.dom") bytes of DOM)"
    fi
    shot "$file" "$name.png" "$size" --virtual-time-budget=1000
    local stats
    if ! stats=$(python3 "$here/png_stats.py" "$name.png"); then
        bad "$file: no screenshot ($(tail -2 "$name.png.log"))"
        return
    fi
    local colours ink
    colours=$(echo "$stats" | sed -E 's/.*colours=([0-9]+).*/\1/')
    ink=$(echo "$stats" | sed -E 's/.*ink=([0-9.]+).*/\1/')
    if [ "$colours" -ge 16 ] && awk -v i="$ink" 'BEGIN { exit !(i >= 0.01) }'; then
        ok "$file: the screenshot draws ($stats)"
    else
        bad "$file: the screenshot looks blank ($stats)"
    fi
}
check_doc demo.html 1280,3000
check_doc anim.svg 200,220
check_doc heat.svg 400,300
check_doc group.svg 340,220
check_doc states.svg 660,200

# 4. SMIL in the DOM, and an animation that moves
n_anim=$(grep -o '<animate ' demo.dom | wc -l)
n_transform=$(grep -o '<animateTransform ' demo.dom | wc -l)
if [ "$n_anim" -ge 10 ] && [ "$n_transform" -ge 1 ]; then
    ok "demo.html: SMIL in the DOM ($n_anim <animate>, $n_transform <animateTransform>)"
else
    bad "demo.html: SMIL in the DOM: $n_anim <animate>, $n_transform <animateTransform>"
fi
shot anim.svg early.png 200,220 --virtual-time-budget=300
shot anim.svg late.png 200,220 --virtual-time-budget=1300
if [ -s early.png ] && [ -s late.png ] && ! cmp -s early.png late.png; then
    ok "anim.svg: the figure moves (screenshots at 0.3 s and 1.3 s differ)"
else
    bad "anim.svg: the screenshots at 0.3 s and 1.3 s are the same (or missing)"
fi
finish
