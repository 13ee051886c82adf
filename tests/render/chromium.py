"""One headless Chromium that prints many pages to PDF, as ``chromium --print-to-pdf`` would.

Each Chromium start costs about a second of CPU, so a test module that prints several sheets
starts one (a module-scoped fixture) and prints every sheet through it. It runs with the flags
the tests gave ``--print-to-pdf`` and a fresh profile, and is driven over the DevTools pipe
(``--remote-debugging-pipe``: NUL-terminated JSON, commands read from fd 3, replies written to
fd 4) with the calls Chromium's own ``--print-to-pdf --no-pdf-header-footer`` makes: a new tab,
the page loaded up to its load event, then Page.printToPDF with the CSS page size, backgrounds, a
tagged PDF and no header or footer. Standard library only.
"""

from __future__ import annotations

import base64
import fcntl
import json
import os
import select
import shutil
import subprocess
import time
from pathlib import Path

FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync")

# what --print-to-pdf --no-pdf-header-footer asks Page.printToPDF for (components/headless)
PRINT_TO_PDF = {"displayHeaderFooter": False, "generateTaggedPDF": True, "printBackground": True,
                "preferCSSPageSize": True}


def find() -> str | None:
    """The Chromium binary on the PATH, or None."""
    return shutil.which("chromium") or shutil.which("chromium-browser")


class Chromium:
    """A headless Chromium with a fresh profile in ``workdir``; ``print_pdf(page)`` prints a page."""

    def __init__(self, binary: str, workdir: Path, timeout: float = 180.0):
        self.timeout, self._id, self._buf, self._events = timeout, 0, b"", []
        commands_r, self._to = os.pipe()
        self._from, replies_w = os.pipe()

        def at_3_and_4():  # in the child, before exec: its ends of the pipes at fd 3 and fd 4
            ends = [fcntl.fcntl(fd, fcntl.F_DUPFD, 10) for fd in (commands_r, replies_w)]
            for fd, end in zip((3, 4), ends):
                os.dup2(end, fd)
                os.close(end)

        self._log = workdir / "chromium.log"
        with open(self._log, "wb") as log:
            self._proc = subprocess.Popen(
                [binary, *FLAGS, f"--user-data-dir={workdir / 'profile'}", "--remote-debugging-pipe"],
                stdin=subprocess.DEVNULL, stdout=log, stderr=log, close_fds=False, preexec_fn=at_3_and_4)
        os.close(commands_r)
        os.close(replies_w)

    def print_pdf(self, page: Path) -> bytes:
        """The PDF of the HTML file ``page``."""
        target = self._call("Target.createTarget", url="about:blank")["targetId"]
        session = self._call("Target.attachToTarget", targetId=target, flatten=True)["sessionId"]
        try:
            self._call("Page.enable", session=session)
            self._call("Page.setLifecycleEventsEnabled", session=session, enabled=True)
            loader = self._call("Page.navigate", session=session, url=page.as_uri())["loaderId"]
            self._event(lambda m: m.get("sessionId") == session and m.get("method") == "Page.lifecycleEvent"
                        and m["params"]["name"] == "load" and m["params"]["loaderId"] == loader)
            data = self._call("Page.printToPDF", session=session, **PRINT_TO_PDF)["data"]
        finally:
            self._call("Target.closeTarget", targetId=target)
            self._events = [m for m in self._events if m.get("sessionId") != session]
        return base64.b64decode(data)

    def evaluate_printed(self, page: Path, expression: str):
        """The value of a JavaScript ``expression`` on the HTML file ``page`` laid out for print
        (CSS print media), returned by value (JSON)."""
        target = self._call("Target.createTarget", url="about:blank")["targetId"]
        session = self._call("Target.attachToTarget", targetId=target, flatten=True)["sessionId"]
        try:
            self._call("Page.enable", session=session)
            self._call("Page.setLifecycleEventsEnabled", session=session, enabled=True)
            self._call("Emulation.setEmulatedMedia", session=session, media="print")
            loader = self._call("Page.navigate", session=session, url=page.as_uri())["loaderId"]
            self._event(lambda m: m.get("sessionId") == session and m.get("method") == "Page.lifecycleEvent"
                        and m["params"]["name"] == "load" and m["params"]["loaderId"] == loader)
            reply = self._call("Runtime.evaluate", session=session, expression=expression, returnByValue=True)
        finally:
            self._call("Target.closeTarget", targetId=target)
            self._events = [m for m in self._events if m.get("sessionId") != session]
        if "exceptionDetails" in reply:
            raise RuntimeError(f"chromium: {reply['exceptionDetails']}")
        return reply["result"]["value"]

    def close(self) -> None:
        """Close the browser and wait for it."""
        try:
            if self._proc.poll() is None:
                self._call("Browser.close")
                self._proc.wait(timeout=30)
        except (OSError, RuntimeError, subprocess.TimeoutExpired):
            self._proc.kill()
            self._proc.wait()
        finally:
            os.close(self._to)
            os.close(self._from)

    def __enter__(self) -> Chromium:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _call(self, method: str, session: str | None = None, **params) -> dict:
        """Send a command and return its result; events read meanwhile are kept for _event."""
        self._id += 1
        message = {"id": self._id, "method": method, "params": params}
        if session is not None:
            message["sessionId"] = session
        data = json.dumps(message).encode() + b"\0"
        while data:
            data = data[os.write(self._to, data):]
        while True:
            reply = self._read()
            if reply.get("id") == self._id:
                if "error" in reply:
                    raise RuntimeError(f"chromium: {method}: {reply['error']}")
                return reply["result"]
            if "method" in reply:
                self._events.append(reply)

    def _event(self, wanted) -> dict:
        """The first event, read already or next, for which ``wanted(message)`` holds."""
        while True:
            for m in self._events:
                if wanted(m):
                    self._events.remove(m)
                    return m
            m = self._read()
            if "method" in m:
                self._events.append(m)

    def _read(self) -> dict:
        deadline = time.monotonic() + self.timeout
        while b"\0" not in self._buf:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self._from], [], [], left)[0]:
                raise RuntimeError(f"chromium: no reply in {self.timeout} s; see {self._log}")
            chunk = os.read(self._from, 1 << 20)
            if not chunk:
                raise RuntimeError(f"chromium ended (exit status {self._proc.poll()}); see {self._log}")
            self._buf += chunk
        message, self._buf = self._buf.split(b"\0", 1)
        return json.loads(message)
