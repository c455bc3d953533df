#!/usr/bin/env python3
"""What a scene author waits for from `rayoflight lsp` on a big scene.

A raw client (no editor between): opens a scene of N spheres, then, each
round, types one character that makes an error in the middle of the file
and deletes it again (one incremental change each, as an editor sends a
keystroke), timing each change to the diagnostics it brings; then asks for
the document's symbols. Prints the medians, the symbols' answer (time and
bytes) and the server's peak memory (VmHWM) against the file's size.

    tools/measure-lsp.py target/release/rayoflight SPHERES [ROUNDS]

Needs python3 only (the scene is written here, ~227 bytes a sphere).
"""
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time


def scene(n):
    lines = ['<?xml version="1.0" encoding="UTF-8"?>', "<scene>"]
    side = int(n ** 0.5) + 1
    for i in range(n):
        x, y = i % side - side / 2, i // side - side / 2
        lines += [
            "  <sphere>",
            '    <color red="0.8" green="0.3" blue="0.2"/>',
            '    <material ka="0.1" kd="0.7" ks="0.3" m="20"/>',
            "    <transformation>",
            f'      <scale factor="0.3"/><translate x="{x}" y="{y}" z="{side}"/>',
            "    </transformation>",
            "  </sphere>",
        ]
    lines += [
        '  <light x="0" y="-5" z="-5"/>',
        '  <camera width="640" height="480" eyeDistance="1"/>',
        '  <model type="phong"/>',
        "</scene>",
        "",
    ]
    return "\n".join(lines)


class Server:
    def __init__(self, binary):
        self.p = subprocess.Popen([binary, "lsp"], stdin=subprocess.PIPE, stdout=subprocess.PIPE)
        self.next_id = 0

    def send(self, message):
        body = json.dumps(dict(message, jsonrpc="2.0")).encode()
        self.p.stdin.write(b"Content-Length: %d\r\n\r\n" % len(body) + body)
        self.p.stdin.flush()

    def receive(self):
        length = 0
        while True:
            line = self.p.stdout.readline()
            if not line:
                raise EOFError("the server ended")
            if line in (b"\r\n", b"\n"):
                break
            if line.lower().startswith(b"content-length:"):
                length = int(line.split(b":")[1])
        body = self.p.stdout.read(length)
        return json.loads(body), len(body)

    def request(self, method, params):
        self.next_id += 1
        self.send({"id": self.next_id, "method": method, "params": params})
        while True:
            message, size = self.receive()
            if message.get("id") == self.next_id and "method" not in message:
                return message, size

    def diagnostics(self):
        while True:
            message, _ = self.receive()
            if message.get("method") == "textDocument/publishDiagnostics":
                return message["params"]["diagnostics"]

    def peak_kib(self):
        with open(f"/proc/{self.p.pid}/status") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1])
        return 0


def main():
    binary, n = sys.argv[1], int(sys.argv[2])
    rounds = int(sys.argv[3]) if len(sys.argv) > 3 else 5
    text = scene(n)
    work = tempfile.mkdtemp()
    path = os.path.join(work, "scene.xml")
    with open(path, "w") as f:
        f.write(text)
    uri = "file://" + path
    server = Server(binary)
    server.request("initialize", {"processId": os.getpid(), "rootUri": None, "capabilities": {}})
    server.send({"method": "initialized", "params": {}})
    start = time.monotonic()
    server.send(
        {
            "method": "textDocument/didOpen",
            "params": {"textDocument": {"uri": uri, "languageId": "xml", "version": 1, "text": text}},
        }
    )
    assert server.diagnostics() == [], "the scene has an error"
    opened = time.monotonic() - start
    peak_open = server.peak_kib()
    # A keystroke in the middle: a letter after the first scale factor of
    # the middle sphere's lines makes its number an error.
    lines = text.split("\n")
    row = next(i for i in range(len(lines) // 2, len(lines)) if "factor=" in lines[i])
    column = lines[row].index('factor="0.3') + len('factor="0.3')
    version, broke, fixed = 1, [], []
    for _ in range(rounds):
        time.sleep(0.3)
        for text_in, end, times, wants_error in (("q", column, broke, True), ("", column + 1, fixed, False)):
            version += 1
            change = {
                "range": {"start": {"line": row, "character": column}, "end": {"line": row, "character": end}},
                "text": text_in,
            }
            start = time.monotonic()
            server.send(
                {
                    "method": "textDocument/didChange",
                    "params": {"textDocument": {"uri": uri, "version": version}, "contentChanges": [change]},
                }
            )
            found = server.diagnostics()
            times.append(time.monotonic() - start)
            assert bool(found) == wants_error, found
            time.sleep(0.3)
    peak_edits = server.peak_kib()
    start = time.monotonic()
    answer, size = server.request("textDocument/documentSymbol", {"textDocument": {"uri": uri}})
    symbols = time.monotonic() - start
    shown = len(answer.get("result") or [])
    peak = server.peak_kib()
    server.request("shutdown", None)
    server.send({"method": "exit"})
    server.p.wait()
    os.unlink(path)
    os.rmdir(work)
    mb = len(text.encode()) / 1e6
    ms = lambda seconds: f"{seconds * 1000:.0f} ms"
    print(
        f"{n} spheres ({mb:.1f} MB): open {ms(opened)}; "
        f"error -> diagnostic median {ms(statistics.median(broke))} (max {ms(max(broke))}); "
        f"fix -> none median {ms(statistics.median(fixed))} (max {ms(max(fixed))}); "
        f"symbols {ms(symbols)}, {size / 1e6:.2f} MB, {shown} at the top; "
        f"peak {peak / 1024:.0f} MiB = {peak * 1024 / len(text.encode()):.2f}x the file "
        f"(after the open {peak_open / 1024:.0f} MiB, after the edits {peak_edits / 1024:.0f} MiB)"
    )


if __name__ == "__main__":
    main()
