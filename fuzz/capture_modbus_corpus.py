#!/usr/bin/env python3
"""Seed corpus for fuzz_modbus_request from real traffic.

    capture_modbus_corpus.py <epa binary> <source dir> <out dir>

Starts `epa serve` (tests/support/epa_appliance.py: registers/epa.csv, unlock key UNLOCK_KEY) and a
recording TCP proxy in front of it, then talks to it through the proxy with real clients: Debian's
mbpoll (float reads with -B, a setpoint write, coils) and pymodbus 3.0 (every function code the
server supports, the unlock and a tuning write, FC23, refusals, another unit id). Every ADU a
client sent is written as one file (adu-NNN.bin), and each client connection's whole byte stream
as one more (session-NNN.bin): the fuzz target cuts streams into ADUs as the server does.
"""
import os
import socket
import subprocess
import sys
import threading

SRC = sys.argv[2]
sys.path.insert(0, os.path.join(SRC, "tests", "support"))
from epa_appliance import UNIT, Appliance, unlock, f32_words, u32_words  # noqa: E402
from pymodbus.client import ModbusTcpClient  # noqa: E402

sessions = []  # bytes each client connection sent


def proxy(listener, port):
    while True:
        try:
            client, _ = listener.accept()
        except OSError:
            return
        server = socket.create_connection(("127.0.0.1", port))
        record = bytearray()
        sessions.append(record)

        def pump(src, dst, rec):
            while True:
                try:
                    data = src.recv(4096)
                except OSError:
                    data = b""
                if not data:
                    for s in (src, dst):
                        try:
                            s.shutdown(socket.SHUT_RDWR)
                        except OSError:
                            pass
                    return
                if rec is not None:
                    rec.extend(data)
                dst.sendall(data)

        threading.Thread(target=pump, args=(client, server, record), daemon=True).start()
        threading.Thread(target=pump, args=(server, client, None), daemon=True).start()


def main():
    epa, out = sys.argv[1], sys.argv[3]
    app = Appliance(epa, os.path.join(SRC, "registers", "epa.csv"))
    listener = socket.socket()
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    listener.bind(("127.0.0.1", 0))
    listener.listen()
    pport = listener.getsockname()[1]
    threading.Thread(target=proxy, args=(listener, app.port), daemon=True).start()
    try:
        mb = ["mbpoll", "-m", "tcp", "-a", "1", "-p", str(pport), "-0", "-1", "-o", "1"]
        for args in (["-t", "3:float", "-B", "-r", "0", "-c", "5"], ["-t", "4:float", "-B", "-r", "0", "-c", "2"],
                     ["-t", "1", "-r", "0", "-c", "4"], ["-t", "0", "-r", "0", "-c", "1"],
                     ["-t", "4:float", "-B", "-r", "0", "127.0.0.1", "50"], ["-t", "4", "-r", "2", "127.0.0.1", "1"],
                     ["-t", "0", "-r", "0", "127.0.0.1", "1"], ["-t", "3:int", "-B", "-r", "122", "-c", "4"]):
            if "127.0.0.1" not in args:
                args = args + ["127.0.0.1"]
            subprocess.run(mb + args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=10)
        c = ModbusTcpClient("127.0.0.1", port=pport, timeout=2, retries=1)
        c.connect()
        c.read_coils(0, 1, slave=UNIT)
        c.read_discrete_inputs(0, 4, slave=UNIT)
        c.read_holding_registers(0, 10, slave=UNIT)
        c.read_holding_registers(20, 10, slave=UNIT)
        c.read_input_registers(0, 11, slave=UNIT)
        c.read_input_registers(20, 42, slave=UNIT)
        c.read_input_registers(70, 14, slave=UNIT)
        c.read_input_registers(90, 14, slave=UNIT)
        c.read_input_registers(110, 20, slave=UNIT)
        c.write_registers(0, f32_words(120.0, "ABCD"), slave=UNIT)
        c.write_register(2, 1, slave=UNIT)
        c.write_register(3, 2, slave=UNIT)
        c.write_registers(6, u32_words(7), slave=UNIT)
        c.write_registers(4, f32_words(1.0, "ABCD"), slave=UNIT)
        c.write_registers(28, f32_words(7.5, "ABCD"), slave=UNIT)
        unlock(c)
        c.write_registers(28, f32_words(7.5, "ABCD"), slave=UNIT)
        c.write_registers(20, f32_words(1.7627, "ABCD") + f32_words(1.0707, "ABCD") + f32_words(1.232, "ABCD")
                          + f32_words(-1.722, "ABCD") + f32_words(5.0, "ABCD"), slave=UNIT)
        c.write_registers(24, f32_words(-2.0, "ABCD"), slave=UNIT)
        c.readwrite_registers(read_address=0, read_count=4, write_address=0, write_registers=f32_words(200.0, "ABCD"),
                              unit=UNIT)
        c.write_registers(0, f32_words(600.0, "ABCD") + [1], slave=UNIT)
        c.write_register(1, 0, slave=UNIT)
        c.write_coil(0, True, slave=UNIT)
        c.write_coils(0, [True], slave=UNIT)
        c.write_coil(1, True, slave=UNIT)
        c.read_holding_registers(0, 2, slave=7)
        c.read_holding_registers(0, 2, slave=0xFF)
        c.write_register(2, 0, slave=UNIT)
        c.close()
    finally:
        listener.close()
        app.stop()
        app.remove()
    os.makedirs(out, exist_ok=True)
    n_adu = 0
    for i, s in enumerate(sessions):
        if not s:
            continue
        with open(os.path.join(out, f"session-{i:03d}.bin"), "wb") as f:
            f.write(s)
        pos = 0
        while len(s) - pos >= 7:
            total = 6 + ((s[pos + 4] << 8) | s[pos + 5])
            with open(os.path.join(out, f"adu-{n_adu:03d}.bin"), "wb") as f:
                f.write(s[pos:pos + total])
            n_adu += 1
            pos += total
    print(f"{len([s for s in sessions if s])} sessions, {n_adu} ADUs in {out}")


if __name__ == "__main__":
    main()
