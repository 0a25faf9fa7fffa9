"""`epa plant-server --control-stdin` on a free loopback port: the simulated remote I/O module,
whose plant a test (or a benchmark) changes while it runs with `physics KEY VALUE` lines and
whose answers it reads back line by line. Stopped by its PID."""
import queue
import subprocess
import threading

from epa_appliance import free_port, stop_process


class PlantServer:
    def __init__(self, epa, plant, initial_position_mm=100.0, extra_args=()):
        self.port = free_port()
        self.proc = subprocess.Popen([epa, "plant-server", "--plant", plant, "--port", str(self.port), "--control-stdin",
                                      "--initial-position", str(initial_position_mm)] + list(extra_args),
                                     stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1)
        self.lines = queue.Queue()
        threading.Thread(target=self._read, daemon=True).start()
        first = self.line(5.0)
        if "listening" not in first:
            stop_process(self.proc)
            raise RuntimeError(f"plant-server did not start: {first!r}")
        self.line(5.0)  # the plant line

    def _read(self):
        for text in self.proc.stdout:
            self.lines.put(text.strip())

    def line(self, timeout_s):
        try:
            return self.lines.get(timeout=timeout_s)
        except queue.Empty:
            return ""

    def command(self, text):
        """Sends one control line and returns the plant-server's answer ("ok ..." or "error: ...")."""
        self.proc.stdin.write(text + "\n")
        self.proc.stdin.flush()
        return self.line(5.0)

    def stop(self):
        stop_process(self.proc)
