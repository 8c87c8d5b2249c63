#!/usr/bin/env python3
"""Drives each simulated twin (`piezobench sim-instrument --dialect
keysight|tektronix|redpitaya`) through PyVISA (the pyvisa-py backend, raw
TCPIP SOCKET resources) with the real instruments' command forms, written
here independently of the C++ drivers: upload a seeded waveform, arm the
acquisition, fire one burst, read both channels back. Checks that every
configuration step leaves the error queue empty and that channel 1 (the
generator's voltage) is the uploaded waveform times the programmed peak,
within half a quantisation step. So the twins are ordinary SCPI instruments
to a third-party client, not only to our drivers.

Usage: pyvisa_twins.py PIEZOBENCH [dialect ...]   (exit 0: all passed)
CTest runs it when a python3 with pyvisa and pyvisa_py is installed.
"""
import json
import math
import random
import socket
import struct
import subprocess
import sys
import time

import pyvisa

N = 1000  # samples per channel (and waveform points)


def free_port_pair():
    for _ in range(50):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        if port >= 65000:
            continue
        with socket.socket() as s2:
            try:
                s2.bind(("127.0.0.1", port + 1))
                return port
            except OSError:
                continue
    raise RuntimeError("no two consecutive free ports")


def poll(ask, done, what, seconds=30.0):
    """Ask until the answer is `done` (a twin simulates the shot when fired: on
    a loaded machine that takes more than a second); a deadline, not a count."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if ask().strip() in done:
            return
        time.sleep(0.005)
    raise AssertionError(f"{what} after {seconds} s")


def seeded_waveform(seed, n):
    rng = random.Random(seed)
    w = [rng.gauss(0.0, 1.0) for _ in range(n)]
    peak = max(abs(x) for x in w)
    # float32 values, as every instrument stores them
    return [struct.unpack("<f", struct.pack("<f", x / peak))[0] for x in w]


class Twin:
    def __init__(self, exe, dialect):
        self.port = free_port_pair()
        self.proc = subprocess.Popen(
            [exe, "sim-instrument", "--host", "127.0.0.1", "--port", str(self.port), "--seconds", "60",
             "--dialect", dialect, "--json"],
            stdout=subprocess.PIPE, text=True)
        text = ""
        while True:  # the ports, as one (pretty-printed) JSON object
            line = self.proc.stdout.readline()
            if not line:
                self.close()
                raise RuntimeError(f"sim-instrument --dialect {dialect} did not start")
            text += line
            try:
                self.ports = json.loads(text)
                break
            except json.JSONDecodeError:
                continue

    def close(self):
        self.proc.terminate()
        self.proc.wait(timeout=10)


def open_socket(rm, port, read_termination="\n"):
    inst = rm.open_resource(f"TCPIP0::127.0.0.1::{port}::SOCKET")
    inst.read_termination = read_termination
    inst.write_termination = "\n"
    inst.timeout = 5000
    return inst


def configure(inst, cmd):
    """A configuration step as the manuals advise: write, *OPC?, SYST:ERR? empty."""
    inst.write(cmd)
    opc = inst.query("*OPC?").strip()
    assert opc in ("1", "+1"), f"{cmd}: *OPC? answered {opc!r}"
    err = inst.query("SYST:ERR?").strip()
    assert err.split(",")[0].lstrip("+") == "0", f"{cmd}: {err}"


def check_v1(name, v1, wave, peak, lsb):
    assert len(v1) >= len(wave), f"{name}: {len(v1)} samples, expected at least {len(wave)}"
    worst = max(abs(v1[k] - peak * wave[k]) for k in range(len(wave)))
    assert worst <= 0.5 * lsb + 1e-9, f"{name}: channel 1 is off the uploaded waveform by {worst} V (LSB {lsb})"
    print(f"{name}: channel 1 = uploaded waveform x {peak} V within {worst:.3g} V (half an LSB = {0.5 * lsb:.3g})")


def infiniium_acquire(rm, port, rate, rng_v, fire):
    """Keysight Infiniium: arm a single acquisition on AUX, fire, read WORD data of both channels."""
    daq = open_socket(rm, port)
    idn = daq.query("*IDN?")
    assert "DSO" in idn or "KEYSIGHT" in idn.upper(), idn
    daq.write("*CLS")
    for cmd in (":SYSTem:HEADer OFF", ":ACQuire:MODE RTIMe", ":CHANnel1:DISPlay ON", ":CHANnel2:DISPlay ON",
                f":CHANnel1:RANGe {2 * rng_v}", f":CHANnel2:RANGe {2 * rng_v}", ":CHANnel1:OFFSet 0",
                ":CHANnel2:OFFSet 0", f":ACQuire:SRATe:ANALog {rate}", f":ACQuire:POINts:ANALog {N}",
                ":TIMebase:REFerence LEFT", ":TIMebase:POSition 0", ":TRIGger:MODE EDGE",
                ":TRIGger:EDGE:SOURce AUX", ":TRIGger:EDGE:SLOPe POSitive", ":WAVeform:FORMat WORD",
                ":WAVeform:BYTeorder LSBFirst", ":WAVeform:STReaming OFF"):
        configure(daq, cmd)
    daq.query(":ADER?")
    daq.write(":SINGle")
    # A query on the same link before the trigger: the scope has taken :SINGle
    # (armed) before the AWG fires on the other link, as the C++ driver does it
    # (without it the trigger could overtake the arm: the twin never acquired).
    err = daq.query(":SYSTem:ERRor?").strip()
    assert err.split(",")[0].lstrip("+") == "0", f":SINGle: {err}"
    fire()
    poll(lambda: daq.query(":ADER?"), ("1", "+1"), ":ADER? never 1 after the burst")
    channels = []
    for ch in (1, 2):
        configure(daq, f":WAVeform:SOURce CHANnel{ch}")
        yinc = float(daq.query(":WAVeform:YINCrement?"))
        yorg = float(daq.query(":WAVeform:YORigin?"))
        codes = daq.query_binary_values(":WAVeform:DATA?", datatype="h", is_big_endian=False)
        assert len(codes) == N, f"channel {ch}: {len(codes)} points"
        channels.append([yorg + yinc * c for c in codes])
    daq.close()
    return channels, rng_v / 8192.0  # 14-bit twin: LSB = range / 2^13


def keysight(rm, twin, wave):
    awg = open_socket(rm, twin.ports["awg_port"])
    assert "33522B" in awg.query("*IDN?")
    awg.write("*CLS")
    rate, peak = 1e7, 1.0
    for cmd in ("OUTPut1 OFF", "SOURce1:DATA:VOLatile:CLEar", "FORMat:BORDer SWAPped"):
        configure(awg, cmd)
    awg.write_binary_values("SOURce1:DATA:ARBitrary PIEZO,", wave, datatype="f", is_big_endian=False)
    configure(awg, "*WAI")
    for cmd in ("SOURce1:FUNCtion:ARBitrary PIEZO", "SOURce1:FUNCtion ARB", f"SOURce1:FUNCtion:ARBitrary:SRATe {rate}",
                "OUTPut1:LOAD INFinity", f"SOURce1:VOLTage {2 * peak}", "SOURce1:VOLTage:OFFSet 0",
                "SOURce1:BURSt:MODE TRIGgered", "SOURce1:BURSt:NCYCles 1", "TRIGger1:SOURce BUS",
                "SOURce1:BURSt:STATe ON", "OUTPut:SYNC ON", "OUTPut1 ON"):
        configure(awg, cmd)
    (v1, v2), lsb = infiniium_acquire(rm, twin.ports["daq_port"], rate, 1.25, lambda: awg.write("*TRG"))
    check_v1("keysight + infiniium", v1, wave, peak, lsb)
    assert any(abs(x) > lsb for x in v2), "channel 2 recorded nothing"
    awg.close()


def tektronix(rm, twin, wave):
    awg = open_socket(rm, twin.ports["awg_port"])
    assert "AWG5014C" in awg.query("*IDN?")
    awg.write("*CLS")
    rate, peak = 1e7, 1.0  # AMPLitude is Vpp into 50 ohm: peak_v, doubled at the high-impedance divider
    configure(awg, "AWGControl:STOP")
    configure(awg, "OUTPut1:STATe OFF")
    configure(awg, f'WLISt:WAVeform:NEW "PIEZO",{len(wave)},REAL')
    # REAL points: little-endian float32 and a marker byte (marker 1 = bit 6), high over the first half
    payload = b"".join(struct.pack("<fB", x, 0x40 if k < len(wave) // 2 else 0) for k, x in enumerate(wave))
    awg.write_binary_values(f'WLISt:WAVeform:DATA "PIEZO",0,{len(wave)},', list(payload), datatype="B")
    configure(awg, "*WAI")
    for cmd in ('SOURce1:WAVeform "PIEZO"', f"SOURce1:FREQuency {rate}", "AWGControl:RMODe TRIGgered",
                "TRIGger:SEQuence:SOURce EXTernal", "SOURce1:MARKer1:DELay 0", "SOURce1:MARKer1:VOLTage:LOW 0",
                "SOURce1:MARKer1:VOLTage:HIGH 1", f"SOURce1:VOLTage:AMPLitude {peak}", "SOURce1:VOLTage:OFFSet 0",
                "AWGControl:RUN"):
        configure(awg, cmd)
    poll(lambda: awg.query("AWGControl:RSTate?"), ("1",), "AWGControl:RSTate? never 1 (waiting for trigger)")
    configure(awg, "OUTPut1:STATe ON")
    (v1, v2), lsb = infiniium_acquire(rm, twin.ports["daq_port"], rate, 1.25, lambda: awg.write("*TRG"))
    check_v1("tektronix + infiniium", v1, wave, peak, lsb)
    assert any(abs(x) > lsb for x in v2), "channel 2 recorded nothing"
    awg.close()


def redpitaya(rm, twin, wave):
    # The server ends its own replies in "\r\n"; the twin's common replies (*IDN?,
    # *OPC?, SYST:ERR?) end in "\n" only: read to "\n" and strip.
    rp = open_socket(rm, twin.ports["port"])
    assert "REDPITAYA" in rp.query("*IDN?").upper()
    rp.write("*CLS")
    buffer_n, decimation = 16384, 8
    pre = 200  # the trigger at sample `pre` of the buffer (ACQ:TRig:DLY = 8192 - pre; |DLY| < 8192)
    rate, peak = 125e6 / decimation, 0.8
    arb = wave + [0.0] * (buffer_n - len(wave))  # the tail is the idle level
    for cmd in ("OUTPUT1:STATE OFF", "SOUR1:FUNC ARBITRARY",
                "SOUR1:TRAC:DATA:DATA " + ",".join(repr(x) for x in arb),
                f"SOUR1:FREQ:FIX {rate / buffer_n!r}", f"SOUR1:VOLT {peak}", "SOUR1:VOLT:OFFS 0",
                "SOUR1:BURS:STAT BURST", "SOUR1:BURS:NCYC 1", "SOUR1:BURS:NOR 1", "SOUR1:TRig:SOUR INT",
                "ACQ:RST", f"ACQ:DEC {decimation}", "ACQ:DATA:FORMAT BIN", "ACQ:DATA:UNITS VOLTS",
                "ACQ:SOUR1:GAIN LV", "ACQ:SOUR2:GAIN LV", f"ACQ:TRig:DLY {buffer_n // 2 - pre}", "OUTPUT1:STATE ON",
                "ACQ:START", "ACQ:TRig AWG_PE"):
        configure(rp, cmd)
    rp.write("SOUR1:TRig:INT")
    for query, done in (("ACQ:TRig:STAT?", "TD"), ("ACQ:TRig:FILL?", "1")):
        poll(lambda: rp.query(query), (done,), f"{query} never {done}")
    rp.read_termination = "\r\n"  # the data blocks are the server's own replies
    v = [rp.query_binary_values(f"ACQ:SOUR{ch}:DATA?", datatype="f", is_big_endian=True) for ch in (1, 2)]
    rp.read_termination = "\n"
    assert len(v[0]) == buffer_n, f"{len(v[0])} samples, expected the buffer's {buffer_n}"
    assert all(abs(x) <= 2.0 ** -13 for x in v[0][:pre]), "channel 1 moved before the trigger"
    check_v1("redpitaya", v[0][pre:], wave, peak, 2.0 ** -13)  # LV: ±1 V in 14 bits
    assert any(abs(x) > 2.0 ** -13 for x in v[1][pre:pre + N]), "channel 2 recorded nothing"
    rp.close()


def main(argv):
    if len(argv) < 2:
        print(__doc__)
        return 2
    exe, dialects = argv[1], argv[2:] or ["keysight", "tektronix", "redpitaya"]
    rm = pyvisa.ResourceManager("@py")
    wave = seeded_waveform(20, N)
    failed = 0
    for dialect in dialects:
        twin = Twin(exe, dialect)
        try:
            {"keysight": keysight, "tektronix": tektronix, "redpitaya": redpitaya}[dialect](rm, twin, wave)
        except Exception as e:  # report every dialect, then fail
            print(f"FAILED {dialect}: {type(e).__name__}: {e}")
            failed += 1
        finally:
            twin.close()
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
