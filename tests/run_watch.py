"""Waiting for a run's own progress before signalling it, so that no test depends on how fast the machine is.

    watch = StderrWatch(process)   a thread reading the process's stderr as it comes (a progress bar has no newline)
    watch.wait_for("steps/s")      until stderr holds the words: the run is at work; fails if it ended first, or
                                   never wrote them within ``seconds`` (a hang, not a slow machine: 10 minutes)
    stdout, stderr = watch.finish()  once the process has ended (its stderr whole, read by the thread alone)
"""

import threading
import time


class StderrWatch:
    def __init__(self, process):
        self.process, self.seen = process, []
        self.thread = threading.Thread(target=lambda: self.seen.extend(iter(lambda: process.stderr.read(1), "")),
                                       daemon=True)
        self.thread.start()

    def text(self) -> str:
        return "".join(self.seen)

    def wait_for(self, words: str, seconds: float = 600) -> None:
        deadline = time.monotonic() + seconds
        while words not in self.text() and self.process.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)
        self.thread.join(0.5 if self.process.poll() is not None else 0)  # what an ended process wrote last
        assert words in self.text(), f"{words!r} never came on stderr: {self.text()[-2000:]}"

    def finish(self, seconds: float = 600) -> tuple[str, str]:
        stdout = self.process.stdout.read()
        self.process.wait(timeout=seconds)
        self.thread.join(timeout=60)
        return stdout, self.text()
