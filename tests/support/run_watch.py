"""Waiting for a run's own output before signalling it, so that no test depends on how fast the machine is.

    watch = OutputWatch(process)            a thread reading the process's stderr (``stream="stdout"``: its
                                            stdout) as it comes (a progress bar has no newline)
    watch.wait_for("steps/s")               until it holds the words: the run is at work; fails if it ended
                                            first, or never wrote them within ``seconds`` (a hang, not a slow
                                            machine: 10 minutes)
    stdout, stderr = watch.finish()         once the process has ended (the watched stream read by the
                                            thread alone, whole)
"""

import threading
import time


class OutputWatch:
    def __init__(self, process, stream: str = "stderr"):
        self.process, self.stream, self.seen = process, stream, []
        source = getattr(process, stream)
        self.thread = threading.Thread(target=lambda: self.seen.extend(iter(lambda: source.read(1), "")), daemon=True)
        self.thread.start()

    def text(self) -> str:
        return "".join(self.seen)

    def wait_for(self, words: str, seconds: float = 600) -> None:
        deadline = time.monotonic() + seconds
        while words not in self.text() and self.process.poll() is None and time.monotonic() < deadline:
            time.sleep(0.05)
        self.thread.join(0.5 if self.process.poll() is not None else 0)  # what an ended process wrote last
        assert words in self.text(), f"{words!r} never came on {self.stream}: {self.text()[-2000:]}"

    def finish(self, seconds: float = 600) -> tuple[str, str]:
        other = (self.process.stdout if self.stream == "stderr" else self.process.stderr).read()
        self.process.wait(timeout=seconds)
        self.thread.join(timeout=60)
        return (other, self.text()) if self.stream == "stderr" else (self.text(), other)
