#!/usr/bin/env python3
"""A pymodbus 3.0 Modbus TCP server for bench/modbus_vs_peers.sh (Debian python3-pymodbus).

Serves 100 holding registers (all zero, 0-based addresses) for any unit id on 127.0.0.1:PORT with
pymodbus' own asyncio TCP server, until SIGTERM/SIGINT or --seconds. Prints
"listening on 127.0.0.1:PORT" once bound. Run it with Debian's interpreter (/usr/bin/python3),
where python3-pymodbus is installed.
"""
import argparse
import asyncio
import logging
import signal
import sys

from pymodbus.datastore import ModbusSequentialDataBlock, ModbusServerContext, ModbusSlaveContext
from pymodbus.server import StartAsyncTcpServer


async def serve(port: int, seconds: float) -> None:
    block = lambda: ModbusSequentialDataBlock(0, [0] * 100)  # noqa: E731
    # zero_mode: protocol address 0 is register 0 (pymodbus otherwise adds 1).
    slave = ModbusSlaveContext(di=block(), co=block(), hr=block(), ir=block(), zero_mode=True)
    context = ModbusServerContext(slaves=slave, single=True)  # single: every unit id
    server = await StartAsyncTcpServer(context=context, address=("127.0.0.1", port),
                                       allow_reuse_address=True, defer_start=True)
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGTERM, signal.SIGINT):
        loop.add_signal_handler(sig, stop.set)
    if seconds > 0:
        loop.call_later(seconds, stop.set)
    task = asyncio.create_task(server.serve_forever())
    await server.serving  # bound and accepting
    print(f"listening on 127.0.0.1:{port}", flush=True)
    await stop.wait()
    await server.server_close()
    task.cancel()
    try:
        await task
    except asyncio.CancelledError:
        pass


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--port", type=int, default=1502, help="TCP port on 127.0.0.1")
    parser.add_argument("--seconds", type=float, default=0.0, help="stop after this long (0: until SIGTERM)")
    args = parser.parse_args()
    logging.basicConfig(level=logging.ERROR)  # pymodbus logs every connection at INFO
    asyncio.run(serve(args.port, args.seconds))
    return 0


if __name__ == "__main__":
    sys.exit(main())
