#!/usr/bin/env bash
# `dicesim show` pages in a real browser: headless Chromium (Debian's `chromium`), inside a private
# network namespace (private_net.sh: only loopback), so the page can reach nothing. Run by CTest:
#   browser.sh DICESIM_BINARY SCENARIO
# Scenarios:
#   show_die   the loaded d20 without a toss: the page loads with no console error, requests no URL
#              but its own file, the canvas has the die drawn (many pixels off the background, the
#              steel region's orange among them) and the info table is in the page text.
#   show_toss  a d20 `impulse` toss opened at its end (#t=end): the same checks, the face read drawn
#              highlighted (gold pixels on the canvas) and the outcome `show` printed in the page text.
#   serve      `dicesim serve` during a `dicesim run` on the same bus: a second serve on the same
#              port is exit 2; once the run ends, /state and the last server-sent event (curl of the
#              stream) show the run's final counts and probabilities.
#   serve_key  an authenticated run (--key-file) and three serves: with its key the page shows the
#              run's counts; without a key (sealed) and with another key (unauthenticated) the page
#              shows no run, counts the messages in its health table and says why.
#   serve_trace `serve --trace-every 1000` during a d20 `impulse` run: the page animates the run's
#              latest 1000th toss in show's viewer: the same data as `show --toss I` (the page's
#              JSON equal), its index and outcome in the page text, its clock running, the view drawn.
# Screenshots are kept in $DICESIM_BROWSER_SHOTS when that is set (to look at them).
set -euo pipefail

. "$(dirname "$0")/private_net.sh" browser "$@"

bin=$1 scenario=$2
command -v chromium > /dev/null || skip "chromium is not installed (scripts/setup installs it)"
fail() { echo "FAIL [$scenario]: $*" >&2; exit 1; }

serve_scenario() {
  local port=18037
  "$bin" serve --port $port > "$work/serve.out" 2> "$work/serve.err" & pids+=($!)
  for _ in $(seq 100); do curl -sf "http://127.0.0.1:$port/state" > /dev/null && break; sleep 0.1; done
  curl -sf "http://127.0.0.1:$port/state" > /dev/null || { cat "$work/serve.err" >&2; fail "serve did not start"; }
  # A port in use: exit 2, the port named, nothing on stdout.
  set +e
  "$bin" serve --port $port > "$work/busy.out" 2> "$work/busy.err"
  rc=$?
  set -e
  [ $rc -eq 2 ] || fail "serve on a busy port exited $rc, expected 2"
  grep -q "127.0.0.1:$port" "$work/busy.err" || fail "the busy port is not named: $(cat "$work/busy.err")"
  [ ! -s "$work/busy.out" ] || fail "serve on a busy port wrote to stdout"
  curl -sN "http://127.0.0.1:$port/events" > "$work/events.txt" & pids+=($!)
  # run's own URL unless told: the bus serve listens on.
  "$bin" run scenes/paper/die1.toml --workers 2 --tosses 300000 --seed 11 --json --lcm "$LCM_DEFAULT_URL" > "$work/run.json" 2> "$work/run.err" ||
    { tail "$work/run.err" >&2; fail "run exited $?"; }
  sleep 1.5  # the final answer reaches serve and its event stream
  curl -sf "http://127.0.0.1:$port/state" > "$work/state.json"
  /usr/bin/python3 - "$work/run.json" "$work/state.json" "$work/events.txt" <<'PY' || fail "the served page does not show the run's final answer"
import json, re, sys
run = json.load(open(sys.argv[1]))
counts = {f["face"]: f["count"] for f in run["faces"]}
ps = {f["face"]: f["p"] for f in run["faces"]}
state = json.load(open(sys.argv[2]))["run"]
assert state["finished"], "the run is not finished in /state"
assert dict(zip(state["labels"], state["counts"])) == counts, (state["counts"], counts)
for label, p in zip(state["labels"], state["p"]):
    assert abs(p - ps[label]) <= 1e-12, (label, p, ps[label])
events = [json.loads(l[6:]) for l in open(sys.argv[3]) if l.startswith("data: ")]
assert len(events) >= 2, "fewer than two server-sent events"
last = events[-1]["run"]
assert last["finished"] and dict(zip(last["labels"], last["counts"])) == counts, "the last event is not the final answer"
print(f"served: {len(events)} events; final counts {counts} on /state and the event stream")
PY
  echo "PASS [$scenario]"
  exit 0
}

# A serve on `port` with `args`, waited for (its /state answers).
start_serve() {
  local port=$1; shift
  "$bin" serve --port "$port" "$@" > "$work/serve-$port.out" 2> "$work/serve-$port.err" & pids+=($!)
  for _ in $(seq 100); do curl -sf "http://127.0.0.1:$port/state" > /dev/null && break; sleep 0.1; done
  curl -sf "http://127.0.0.1:$port/state" > /dev/null || { cat "$work/serve-$port.err" >&2; fail "serve on $port did not start"; }
}

# The live page at `url` as Chromium shows it after BROWSE_S (3) seconds of real time: its DOM
# ($work/WHAT-dom.out), a screenshot ($work/WHAT.png); no console error or uncaught exception.
# (The page keeps its event stream open, so --virtual-time-budget would never end and --dump-dom
# alone does not wait: cdp_page.py drives Chromium over the DevTools protocol instead.)
browse_live() {
  local what=$1 url=$2
  timeout 120 /usr/bin/python3 tests/integration/cdp_page.py "$url" "${BROWSE_S:-3}" "$work/$what-dom.out" "$work/$what.png" \
    "$work/$what-errors.txt" || fail "chromium ($what) failed"
  if [ -n "${DICESIM_BROWSER_SHOTS:-}" ]; then mkdir -p "$DICESIM_BROWSER_SHOTS"; cp "$work/$what.png" "$DICESIM_BROWSER_SHOTS/$what.png"; fi
  [ ! -s "$work/$what-errors.txt" ] || { cat "$work/$what-errors.txt" >&2; fail "the page ($what) logged an error"; }
}

# An authenticated run (--key-file) followed by three serves: with the run's key it shows the run's
# counts; without a key, and with another key, it shows no run but counts what it heard (sealed,
# and unauthenticated) in the page's health table, with a note saying why nothing is shown.
serve_key_scenario() {
  local key=$work/run.key other=$work/other.key
  (umask 077; od -An -tx1 -N32 /dev/urandom | tr -d ' \n' > "$key"; od -An -tx1 -N32 /dev/urandom | tr -d ' \n' > "$other")
  start_serve 18041 --key-file "$key"
  start_serve 18042
  start_serve 18043 --key-file "$other"
  "$bin" run scenes/paper/die1.toml --workers 2 --tosses 100000 --seed 12 --json --key-file "$key" --lcm "$LCM_DEFAULT_URL" \
    > "$work/run.json" 2> "$work/run.err" || { tail "$work/run.err" >&2; fail "run exited $?"; }
  sleep 1.5  # the final answer reaches the serves
  for port in 18041 18042 18043; do
    browse_live "serve-$port" "http://127.0.0.1:$port/"
    curl -sf "http://127.0.0.1:$port/state" > "$work/state-$port.json"
  done
  /usr/bin/python3 - "$work" <<'PY' || fail "the serves do not show what their key opens"
import json, re, sys
work = sys.argv[1]
run = json.load(open(f"{work}/run.json"))
counts = {str(f["face"]): f["count"] for f in run["faces"]}
def page(port):
    dom = open(f"{work}/serve-{port}-dom.out").read()
    cell = lambda i: int(re.search(f'id="{i}">([0-9]+)<', dom).group(1))
    shown = dict(re.findall(r'<span class="p" data-label="([0-9]+)">[^<]*</span>[^<]*<span class="count">([0-9]+)</span>', dom))
    auth = re.search(r'<p id="auth"( hidden="")?>([^<]*)</p>', dom)
    return json.load(open(f"{work}/state-{port}.json")), {k: int(v) for k, v in shown.items()}, cell, auth
state, shown, cell, auth = page(18041)  # the run's key
assert state["run"] and state["run"]["finished"], "the keyed serve shows no finished run"
assert dict(zip(map(str, state["run"]["labels"]), state["run"]["counts"])) == counts, (state["run"]["counts"], counts)
assert shown == counts, f"the keyed page shows {shown}, the run counted {counts}"
assert state["heard"]["unauthenticated"] == 0 and state["heard"]["sealed"] == 0, state["heard"]
assert cell("heard-unauthenticated") == 0 and auth.group(1), "the keyed page reports unauthenticated messages"
state, shown, cell, auth = page(18042)  # no key
assert state["run"] is None and not shown, "a serve without the key shows the sealed run"
sealed = cell("heard-sealed")
assert state["heard"]["sealed"] > 0 and sealed > 0, "a serve without the key counts no sealed messages"
assert not auth.group(1) and "--key-file" in auth.group(2), f"no note on the page without the key: {auth.group(0)}"
state, shown, cell, auth = page(18043)  # another key
assert state["run"] is None and not shown, "a serve with another key shows the run"
unauthenticated = cell("heard-unauthenticated")
assert state["heard"]["unauthenticated"] > 0 and unauthenticated > 0, "a serve with another key counts nothing unauthenticated"
assert not auth.group(1) and "HMAC" in auth.group(2), f"no note on the page with another key: {auth.group(0)}"
print(f"keyed serve: counts {counts} on the page; on the pages without a key: {sealed} sealed, with another key:",
      f"{unauthenticated} unauthenticated")
PY
  echo "PASS [$scenario]"
  exit 0
}

# serve --trace-every during a d20 `impulse` run: the page animates, in show's viewer, the run's
# latest K-th toss, made by serve itself; it is the toss `show --toss I` makes (the same page
# data), its index and outcome are in the page text, its clock runs, and the view is drawn.
serve_trace_scenario() {
  local port=18045 every=1000 tosses=20000 seed=13 scene=scenes/dice/d20.toml
  start_serve $port --trace-every $every
  "$bin" run $scene --fidelity impulse --workers 2 --tosses $tosses --seed $seed --json --lcm "$LCM_DEFAULT_URL" \
    > "$work/run.json" 2> "$work/run.err" || { tail "$work/run.err" >&2; fail "run exited $?"; }
  sleep 1.5  # the final answer reaches serve
  curl -sf "http://127.0.0.1:$port/state" > "$work/state.json"
  local index=$((every * ((tosses - 1) / every)))
  local run
  run=$(/usr/bin/python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["trace"]["run"])' "$work/state.json")
  curl -sf "http://127.0.0.1:$port/trace?run=$run&index=$index" > "$work/trace.html" || fail "GET /trace of toss $index failed"
  code=$(curl -s -o "$work/unknown.html" -w '%{http_code}' "http://127.0.0.1:$port/trace?run=1&index=0")
  [ "$code" = 404 ] && grep -q 'id="trace-error"' "$work/unknown.html" || fail "an unknown run's trace is $code, not 404 with a reason"
  "$bin" show $scene --fidelity impulse --seed $seed --tosses $tosses --toss $index -o "$work/show.html" 2> "$work/show.err" ||
    { cat "$work/show.err" >&2; fail "show exited $?"; }
  # Under load the page may start playing late: wait (up to 30 s more) for its clock to pass 1 s
  # of the 1.57 s toss, when the die is down among its impacts. (Earlier, in flight, the camera
  # follows it up and the floor, whose pixels the check below takes as the view, shrinks away
  # from it: CI at clock 0.429 s saw 7.3 % of the page as the view and no die in it.)
  CDP_UNTIL="parseFloat(((document.getElementById('trace-clock') || {}).textContent || '').replace(/^.*t = /, '')) > 1.0" \
    BROWSE_S=${BROWSE_S:-8} browse_live serve-trace "http://127.0.0.1:$port/"
  /usr/bin/python3 - "$work" "$index" "$every" <<'PY' || fail "the served page does not animate show's toss $index"
import json, re, sys
from PIL import Image
work, index, every = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
data = lambda path: json.loads(re.search(r'<script id="dicesim-data" type="application/json">(.*?)</script>',
                                         open(path).read(), re.S).group(1).replace("<\\/", "</"))
state = json.load(open(f"{work}/state.json"))
assert state["run"]["finished"], "the run is not finished"
tr = state["trace"]
assert tr["every"] == every and tr["index"] == index and tr["run_start"], tr
served, shown = data(f"{work}/trace.html"), data(f"{work}/show.html")
assert served["toss"] == shown["toss"], "serve's toss is not show --toss's"
assert served["die"] == shown["die"] and served["info"] == shown["info"], "serve's die is not show's"
toss = shown["toss"]
assert toss["interpolated"] == [], f"stretches interpolated: {toss['interpolated']}"
assert toss["steps_recorded"] > 0, "no sustained contact recorded: pick a toss that has some"
dom = open(f"{work}/serve-trace-dom.out").read()
cell = lambda i: re.search(f'id="{i}">([^<]*)<', dom)
assert cell("trace-index") and int(cell("trace-index").group(1)) == index, f"the page shows toss {cell('trace-index')}, not {index}"
assert cell("trace-outcome").group(1) == toss["outcome"], (cell("trace-outcome").group(1), toss["outcome"])
clock = re.search(r"t = ([0-9.]+) s", cell("trace-clock").group(1))
assert clock and float(clock.group(1)) > 0, f"the toss is not playing: clock {cell('trace-clock').group(1)!r}"
# The view: the 3-D floor and die (warm greys: r - b >= 12) cover a share of the page; the serve
# page's own colours are neutral or blue, and a blank canvas shows the scene's neutral background.
img = Image.open(f"{work}/serve-trace.png").convert("RGB")
px = list(img.getdata())
is_warm = lambda p: p[0] > 150 and p[0] - p[2] >= 12 and p[0] - p[1] <= 20
warm = sum(1 for p in px if is_warm(p))
# The die in it: its label digits are dark pixels inside the view (the box of the warm pixels,
# 1st to 99th percentile: a few antialiased text pixels elsewhere are warm too).
w = img.size[0]
xs = sorted(i % w for i, p in enumerate(px) if is_warm(p)) or [0]
ys = sorted(i // w for i, p in enumerate(px) if is_warm(p)) or [0]
q = lambda v, f: v[int(f * (len(v) - 1))]
view = img.crop((q(xs, 0.01), q(ys, 0.01), q(xs, 0.99) + 1, q(ys, 0.99) + 1))
dark = sum(1 for p in view.getdata() if max(p) < 80)
print(f"serve --trace-every {every}: toss {index} outcome {toss['outcome']} ({toss['bounces']} impacts, "
      f"{toss['steps_recorded']} sustained-contact states recorded), clock {clock.group(1)} s; {warm / len(px):.1%} of the page is the 3-D view's, "
      f"{dark} dark pixels in it")
assert warm > 0.03 * len(px), "the sampled toss is not drawn"
assert dark > 50, "the die is not in the view"
PY
  echo "PASS [$scenario]"
  exit 0
}

case "$scenario" in
  serve) serve_scenario ;;
  serve_key) serve_key_scenario ;;
  serve_trace) serve_trace_scenario ;;
  show_die) scene=scenes/dice/loaded-d20.toml; args=(); hash="" ;;
  show_toss) scene=scenes/dice/d20.toml; args=(--fidelity impulse --toss 7); hash="#t=end" ;;
  *) fail "unknown scenario" ;;
esac
page=$work/page.html
"$bin" show "$scene" "${args[@]}" -o "$page" 2> "$work/show.err" || { cat "$work/show.err" >&2; fail "show exited $?"; }
cat "$work/show.err"

# One browser run: software WebGL (SwiftShader), no background traffic, a net log of every request.
browse() {
  local what=$1; shift
  timeout 90 chromium --headless=new --no-sandbox --disable-gpu --use-angle=swiftshader --enable-unsafe-swiftshader \
    --no-first-run --no-default-browser-check --disable-background-networking --disable-component-update \
    --disable-sync --disable-extensions --user-data-dir="$work/profile-$what" --window-size=1280,800 \
    --enable-logging=stderr --v=0 --log-net-log="$work/net-$what.json" --virtual-time-budget=4000 \
    "$@" "file://$page$hash" > "$work/$what.out" 2> "$work/$what.err" || { tail -20 "$work/$what.err" >&2; fail "chromium ($what) exited $?"; }
}
browse shot --screenshot="$work/shot.png"
browse dom --dump-dom

# No console error or uncaught exception (Chromium logs the page's console as CONSOLE lines).
if grep -E 'CONSOLE|Uncaught' "$work/shot.err" "$work/dom.err" | grep -viE '"(log|info|debug)"' | grep -iE 'error|uncaught'; then
  fail "the page logged an error"
fi
grep -E 'CONSOLE' "$work/shot.err" "$work/dom.err" || true

# Requests: every URL the page asked for is the page itself (or inline: data:, blob:). Chromium's
# own background requests (component updates, network time; initiator "not an origin") fail in
# the namespace and are not the page's.
/usr/bin/python3 - "file://$page" "$work/net-shot.json" "$work/net-dom.json" <<'PY' || fail "the page requested something outside its file"
import json, sys
page = sys.argv[1]
bad, own = set(), set()
for path in sys.argv[2:]:
    d = json.load(open(path))
    names = {v: k for k, v in d["constants"]["logEventTypes"].items()}
    for e in d["events"]:
        p = e.get("params", {})
        if names.get(e["type"]) != "URL_REQUEST_START_JOB" or "url" not in p:
            continue
        url = p["url"]
        if p.get("initiator") == "not an origin":
            own.add(url.split("?")[0])
        elif url.split("#")[0] != page and not url.startswith(("data:", "blob:")):
            bad.add(url)
print(f"requests: none by the page; {len(own)} of the browser's own (ignored)")
for u in sorted(bad):
    print("the page requested:", u)
sys.exit(1 if bad else 0)
PY

# The page text: the info table, and the toss's outcome as `show` named it.
grep -q 'principal moments' "$work/dom.out" || fail "no info table in the page text"
if [ "$scenario" = show_toss ]; then
  outcome=$(sed -nE 's/.*outcome ([0-9a-z/]+), .*/\1/p' "$work/show.err")
  [ -n "$outcome" ] || fail "show printed no outcome"
  grep -q "id=\"outcome-label\">$outcome<" "$work/dom.out" || fail "outcome $outcome is not in the page text"
  grep -q 'class="m ' "$work/dom.out" || fail "no impact marked on the timeline"
fi

# The canvas: the die drawn (pixels of the 3-D view that are not its background).
[ -s "$work/shot.png" ] || fail "no screenshot"
if [ -n "${DICESIM_BROWSER_SHOTS:-}" ]; then mkdir -p "$DICESIM_BROWSER_SHOTS"; cp "$work/shot.png" "$DICESIM_BROWSER_SHOTS/$scenario.png"; fi
/usr/bin/python3 - "$work/shot.png" "$scenario" <<'PY' || fail "the die is not drawn in the screenshot"
import sys
from PIL import Image
img = Image.open(sys.argv[1]).convert("RGB")
w, h = img.size
view = img.crop((0, 0, int(w * 0.55), h))  # the 3-D view is the left 60 % of the page
px = list(view.getdata())
bg = (0xf4, 0xf4, 0xf1)
# A canvas never drawn is blank (black in Chromium's screenshot, 100 % "off the background" and
# "dark"): the renderer's clear to the scene's background must cover much of the view, and the die
# on it must be shaded (many colours), with some dark label pixels but not a dark view.
on_bg = sum(1 for p in px if sum(abs(a - b) for a, b in zip(p, bg)) <= 30)
off = len(px) - on_bg
colours = len({p for p in px if sum(abs(a - b) for a, b in zip(p, bg)) > 30})
dark = sum(1 for p in px if max(p) < 80)  # label digits
gold = sum(1 for p in px if p[0] > 200 and p[1] > 190 and p[2] < 150 and p[0] - p[2] > 90)  # the face read (yellow)
orange = sum(1 for p in px if p[0] > 170 and 90 < p[1] < 190 and p[2] < 140 and p[0] - p[1] > 50)  # a steel region
n = len(px)
print(f"{w}x{h}: {on_bg / n:.1%} of the view the scene's background, {off / n:.1%} off it in {colours} colours,",
      f"{dark} dark, {gold} gold, {orange} orange pixels")
ok = on_bg > 0.2 * n and off > 0.02 * n and colours > 50 and 50 < dark < 0.1 * n
if sys.argv[2] == "show_toss":
    ok = ok and gold > 100
else:
    ok = ok and orange > 100
sys.exit(0 if ok else 1)
PY
echo "PASS [$scenario]"
