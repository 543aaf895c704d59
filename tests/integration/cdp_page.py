#!/usr/bin/python3
"""A live page in headless Chromium for the browser tests: opens URL, lets it run for SECONDS of
real time (a page that keeps an event stream open never lets --virtual-time-budget end, and
--dump-dom alone does not wait), then writes its DOM and a screenshot. Drives Chromium over the
DevTools protocol on a pipe (--remote-debugging-pipe: fds 3 and 4, NUL-separated JSON), so it
needs nothing but the standard library. Console errors and uncaught exceptions (of the page and
its frames) are written to ERRORS, one a line.

    cdp_page.py URL SECONDS DOM.html SHOT.png ERRORS.txt [WIDTHxHEIGHT]

Environment: CDP_UNTIL, a JavaScript condition to wait for after SECONDS (CDP_UNTIL_MAX s at most).
"""
import base64
import json
import os
import select
import subprocess
import sys
import tempfile
import time

url, seconds, dom_path, shot_path, errors_path = sys.argv[1], float(sys.argv[2]), sys.argv[3], sys.argv[4], sys.argv[5]
width, height = (int(x) for x in (sys.argv[6] if len(sys.argv) > 6 else "1280x1400").split("x"))

to_chrome_r, to_chrome_w = os.pipe()
from_chrome_r, from_chrome_w = os.pipe()


def child_fds():  # the pipe's ends as fds 3 and 4, kept across exec (dup2 makes them inheritable)
    a, b = os.dup(to_chrome_r), os.dup(from_chrome_w)
    os.dup2(a, 3)
    os.dup2(b, 4)


profile = tempfile.mkdtemp(prefix="dicesim-cdp-")
chrome = subprocess.Popen(
    ["chromium", "--headless=new", "--no-sandbox", "--disable-gpu", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
     "--no-first-run", "--no-default-browser-check", "--disable-background-networking", "--disable-component-update",
     "--disable-sync", "--disable-extensions", f"--user-data-dir={profile}", f"--window-size={width},{height}",
     "--remote-debugging-pipe", "about:blank"],
    stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    preexec_fn=child_fds, close_fds=False)
os.close(to_chrome_r)
os.close(from_chrome_w)

buf = b""
next_id = 0
errors = []


def on_event(msg):
    method, p = msg.get("method"), msg.get("params", {})
    if method == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
        errors.append("console." + p["type"] + ": " + " ".join(str(a.get("value", a.get("description", ""))) for a in p.get("args", [])))
    elif method == "Runtime.exceptionThrown":
        d = p.get("exceptionDetails", {})
        errors.append("uncaught: " + d.get("text", "") + " " + str(d.get("exception", {}).get("description", "")))
    elif method == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
        e = p["entry"]
        errors.append(f"log ({e.get('source')}): {e.get('text')} {e.get('url', '')}")


def read_messages(timeout):
    global buf
    ready, _, _ = select.select([from_chrome_r], [], [], max(0.0, timeout))
    if not ready:
        return []
    chunk = os.read(from_chrome_r, 1 << 20)
    if not chunk:
        raise SystemExit("chromium closed the DevTools pipe")
    buf += chunk
    *done, buf = buf.split(b"\0")
    return [json.loads(m) for m in done]


def call(method, params=None, session=None, timeout=60):
    global next_id
    next_id += 1
    msg = {"id": next_id, "method": method, "params": params or {}}
    if session:
        msg["sessionId"] = session
    os.write(to_chrome_w, json.dumps(msg).encode() + b"\0")
    end = time.time() + timeout
    while time.time() < end:
        for m in read_messages(end - time.time()):
            if m.get("id") == next_id:
                if "error" in m:
                    raise SystemExit(f"{method}: {m['error']}")
                return m.get("result", {})
            on_event(m)
    raise SystemExit(f"{method}: no answer in {timeout} s")


def pump(secs):
    end = time.time() + secs
    while time.time() < end:
        for m in read_messages(end - time.time()):
            on_event(m)


try:
    target = call("Target.createTarget", {"url": "about:blank"})["targetId"]
    session = call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
    for domain in ("Page", "Runtime", "Log"):
        call(domain + ".enable", session=session)
    call("Emulation.setDeviceMetricsOverride", {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False},
         session=session)
    call("Page.navigate", {"url": url}, session=session)
    pump(seconds)
    # CDP_UNTIL (a JavaScript expression): then keep the page running, up to CDP_UNTIL_MAX more
    # seconds (default 30), until it is true. A loaded machine can leave swiftshader's WebGL page
    # not yet animating after SECONDS (the test's own assertion still decides).
    until, waited = os.environ.get("CDP_UNTIL"), 0.0
    while until and waited < float(os.environ.get("CDP_UNTIL_MAX", "30")):
        if call("Runtime.evaluate", {"expression": f"!!({until})", "returnByValue": True}, session=session)["result"].get("value"):
            break
        pump(0.5)
        waited += 0.5
    dom = call("Runtime.evaluate", {"expression": "document.documentElement.outerHTML", "returnByValue": True},
               session=session)["result"]["value"]
    open(dom_path, "w").write(dom)
    shot = call("Page.captureScreenshot", {"format": "png"}, session=session)["data"]
    open(shot_path, "wb").write(base64.b64decode(shot))
    open(errors_path, "w").write("".join(e + "\n" for e in errors))
    try:
        call("Browser.close", timeout=5)
    except SystemExit:
        pass
finally:
    try:
        chrome.wait(timeout=10)
    except subprocess.TimeoutExpired:
        chrome.kill()
        chrome.wait()
    subprocess.run(["rm", "-rf", profile])
