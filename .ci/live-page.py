#!/usr/bin/env python3
"""The live page of `psdcal serve` in headless Chromium, driven over the
DevTools protocol on a pipe (--remote-debugging-pipe: JSON messages ended by
NUL on file descriptors 3 and 4; no WebSocket, nothing but the standard
library). One page session: load the page, screenshot after 2.5 s and again
2 s later; then the page's text. Fails on a console error or exception, a
request to another host than the server's, a sensor missing from the page's
table, a (nearly) blank screenshot, or two screenshots that do not differ.

Usage: live-page.py URL PREFIX SENSOR... (writes PREFIX-1.png, PREFIX-2.png)
"""
import base64
import fcntl
import json
import os
import queue
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import urllib.parse
import struct
import zlib

url, prefix, sensors = sys.argv[1], sys.argv[2], sys.argv[3:]
profile = tempfile.mkdtemp(prefix="live-page-profile-")


def high(fd):
    """`fd` moved to a number of 10 or more (3 and 4 are Chromium's)."""
    moved = fcntl.fcntl(fd, fcntl.F_DUPFD, 10)
    os.close(fd)
    return moved


to_chrome_r, to_chrome_w = map(high, os.pipe())
from_chrome_r, from_chrome_w = map(high, os.pipe())
# Chromium reads commands on fd 3 and writes answers on fd 4.
os.dup2(to_chrome_r, 3)
os.dup2(from_chrome_w, 4)
chrome = subprocess.Popen(
    ["chromium", "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
     "--no-first-run", "--disable-background-networking", "--disable-component-update",
     "--disable-sync", "--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1",
     f"--user-data-dir={profile}", "--hide-scrollbars", "--window-size=1200,900",
     "--remote-debugging-pipe", "about:blank"],
    pass_fds=(3, 4), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
)
for fd in (3, 4, to_chrome_r, from_chrome_w):
    os.close(fd)
answers, events = {}, queue.Queue()


def read_messages():
    buf = b""
    with os.fdopen(from_chrome_r, "rb", buffering=0) as f:
        while chunk := f.read(65536):
            buf += chunk
            while b"\0" in buf:
                msg, buf = buf.split(b"\0", 1)
                m = json.loads(msg)
                if "id" in m:
                    answers[m["id"]] = m
                else:
                    events.put(m)


threading.Thread(target=read_messages, daemon=True).start()
out = os.fdopen(to_chrome_w, "wb", buffering=0)
next_id = [0]


def send(method, session=None, **params):
    next_id[0] += 1
    n = next_id[0]
    m = {"id": n, "method": method, "params": params}
    if session:
        m["sessionId"] = session
    out.write(json.dumps(m).encode() + b"\0")
    deadline = time.time() + 30
    while n not in answers:
        if time.time() > deadline:
            sys.exit(f"live-page: FAIL: no answer to {method} from chromium")
        time.sleep(0.01)
    a = answers.pop(n)
    if "error" in a:
        sys.exit(f"live-page: FAIL: {method}: {a['error']}")
    return a["result"]


problems, hosts = [], set()


def drain():
    while not events.empty():
        e = events.get()
        method, p = e.get("method"), e.get("params", {})
        if method == "Runtime.exceptionThrown":
            problems.append(f"exception: {p['exceptionDetails'].get('text')} "
                            f"{p['exceptionDetails'].get('exception', {}).get('description', '')}")
        elif method == "Runtime.consoleAPICalled" and p.get("type") in ("error", "warning", "assert"):
            problems.append(f"console {p['type']}: {[a.get('value') for a in p.get('args', [])]}")
        elif method == "Log.entryAdded" and p["entry"].get("level") == "error":
            problems.append(f"log: {p['entry'].get('text')} {p['entry'].get('url', '')}")
        elif method == "Network.requestWillBeSent":
            hosts.add(urllib.parse.urlsplit(p["request"]["url"]).netloc)


def pixels(png):
    pos, idat = 8, b""
    while pos < len(png):
        n, kind = struct.unpack(">I4s", png[pos:pos + 8])
        if kind == b"IDAT":
            idat += png[pos + 8:pos + 8 + n]
        pos += 12 + n
    return zlib.decompress(idat)


try:
    page = next(t for t in send("Target.getTargets")["targetInfos"] if t["type"] == "page")
    s = send("Target.attachToTarget", targetId=page["targetId"], flatten=True)["sessionId"]
    for domain in ("Page", "Runtime", "Log", "Network"):
        send(f"{domain}.enable", s)
    send("Page.navigate", s, url=url)
    shots = []
    for wait in (2.5, 2.0):
        time.sleep(wait)
        png = base64.b64decode(send("Page.captureScreenshot", s, format="png")["data"])
        shots.append(png)
    text = send("Runtime.evaluate", s, expression="document.body.innerText",
                returnByValue=True)["result"].get("value", "")
    time.sleep(0.2)
    drain()
    try:
        send("Browser.close")
    except SystemExit:
        pass
finally:
    try:
        chrome.wait(timeout=10)
    except subprocess.TimeoutExpired:
        chrome.kill()
        chrome.wait()
    shutil.rmtree(profile, ignore_errors=True)

for k, png in enumerate(shots, 1):
    with open(f"{prefix}-{k}.png", "wb") as f:
        f.write(png)
server = urllib.parse.urlsplit(url).netloc
failures = list(problems)
foreign = sorted(h for h in hosts if h and h != server)
if foreign:
    failures.append(f"requests to other hosts: {foreign}")
missing = [sid for sid in sensors if sid not in text.split()]
if missing:
    failures.append(f"sensors missing from the page: {missing}")
a, b = pixels(shots[0]), pixels(shots[1])
if len(set(a[::97])) <= 20:
    failures.append("the first screenshot is (nearly) blank")
differ = sum(x != y for x, y in zip(a, b))
print(f"live-page: requests to {sorted(hosts)}; sensors {sensors} in the page; "
      f"the screenshots 2 s apart differ in {differ} bytes")
if differ <= 100:
    failures.append("the page did not change in 2 s")
for f in failures:
    print(f"live-page: FAIL: {f}", file=sys.stderr)
sys.exit(1 if failures else 0)
