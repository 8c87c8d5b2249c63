#!/usr/bin/python3
"""Writes the seed corpus of the fuzz harnesses: tests/fuzz/corpus/<name>/.

Deterministic (fixed seeds); run from anywhere:
    /usr/bin/python3 tests/fuzz/make_corpus.py
Small valid inputs, a few KB each: instrument byte streams and replies, the
README's plan and one per excitation, CSV and Touchstone impedance files of a
Butterworth-Van Dyke resonator (and the same in every format dsp/impedance_files
reads), and capture recipes (fuzz_capture reads its
input as decisions; a zero byte is always the ordinary valid choice, so the
empty recipe is a valid one-shot capture and sparse recipes are mostly valid).
"""
import cmath
import math
import os
import random

HERE = os.path.dirname(os.path.abspath(__file__))


def write(harness, name, data):
    d = os.path.join(HERE, "corpus", harness)
    os.makedirs(d, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


# ---------------------------------------------------------------- block_parser
# Layout: byte 0 = k, then k control bytes, then the stream. Control bytes, in
# order: framer cut count and cut sizes; client piece count and sizes, EOM
# bits, op count - 1, ops (0 query, 1 query_double, 2 query_block,
# 3 check_errors, 4 configure, 5 identify).
def stream(ctl, s):
    return bytes([len(ctl)]) + bytes(ctl) + (s.encode("latin-1") if isinstance(s, str) else s)


QUERY_BLOCK = [0, 0, 0, 0, 2]  # no cuts, no pieces, no EOM bits, one op: query_block
block = {
    "idn_reply": stream([0, 0, 0, 0, 5], "Keysight Technologies,33522B,MY52001234,4.03-1.19-2.00-52-00\n"),
    "block_small": stream(QUERY_BLOCK, "#15hello\n"),
    "block_newlines": stream(QUERY_BLOCK, "#211ab\ncd\nef\ngh\n"),
    "block_words": stream(QUERY_BLOCK, b"#216" + bytes(range(16)) + b"\n"),
    "block_leading_zeros": stream([2, 3, 5, 2, 7, 0x55, 1, 2, 2], "#800000004abcd\n#10\n"),
    "error_queue": stream([0, 0, 0, 0, 3], '-113,"Undefined header"\n-222,"Data out of range"\n+0,"No error"\n'),
    "configure_ok": stream([0, 0, 0, 0, 4], '1\n+0,"No error"\n'),
    "number_reply": stream([0, 0, 0, 1, 1, 1], "+1.00000000E+07\n-0.5\n"),
    "awg_session": stream([0],
                          "*IDN?\n*RST;*CLS\nFORM:BORD SWAP\nSOUR1:DATA:VOL:CLE\n"
                          "SOUR1:DATA:ARB PIEZO,#216" + "\x00\x00\x80\x3f" * 4 + "\n"
                          "SOUR1:FUNC:ARB PIEZO\nSOUR1:FUNC:ARB:SRAT 1E7\nSOUR1:VOLT 2.0\n"
                          "OUTP1 ON\nTRIG1:SOUR BUS\n*TRG\n*OPC?\nSYST:ERR?\n"),
    "daq_session": stream([3, 5, 17, 40],
                          ":ACQ:POIN:ANAL 20000;:ACQ:SRAT:ANAL 1e7\r\nCHAN1:RANG 2.5\nCHAN2:RANG?\n"
                          "WAV:SOUR CHAN2\nWAV:FORM WORD\nWAV:BYT LSBF\n:SING\n:ADER?\nWAV:DATA?\n"),
    "strings_and_hash": stream([0], 'DISP:TEXT "Ch#1 ok; done"\nSOUR:VOLT #H1F\nSYST:COMM \'a#2b\'\n'),
    "usbtmc_header": stream([0], bytes([2, 0, 0xFF, 0, 5, 0, 0, 0, 1, 0, 0, 0]) + b"hello\n"),
}

# ---------------------------------------------------------------- plan
README_PLAN = """[excitation]
kind = "exp_decay"      # exp_decay | sine | chirp | noise
amplitude_v = 1.0
decay_per_s = 3000.0

[acquisition]
sample_rate_hz = 1e7
samples = 20000
pretrigger_samples = 200
shots = 4

[setup]
r1_ohm = 3140.0
transducer_id = "T-017"
material = "apc850"
"""
plans = {
    "readme.toml": README_PLAN,
    "sine.toml": '[excitation]\nkind = "sine"\namplitude_v = 0.5\nfrequency_hz = 48000.0\n'
                 "[acquisition]\nsample_rate_hz = 2e6\nsamples = 4096\npretrigger_samples = 0\n",
    "stepped_sine.toml": '[excitation]\nkind = "sine"\nfrequency_hz = 40e3\nf_start_hz = 40e3\n'
                         "f_stop_hz = 60e3\nf_step_hz = 500.0\n[acquisition]\nsample_rate_hz = 1e6\n"
                         "samples = 2000\npretrigger_samples = 16\nshots = 2\n",
    "chirp.toml": '[excitation]\nkind = "chirp"\nf_start_hz = 1e3\nf_stop_hz = 120e3\nburst_fraction = 0.5\n'
                  "[acquisition]\nsample_rate_hz = 1e7\nsamples = 16\npretrigger_samples = 2\nrange_v = 2.5\n",
    "noise.toml": '[excitation]\nkind = "noise"\nseed = 42\nburst_fraction = 0.25\namplitude_v = 10\n'
                  "[acquisition]\nsamples = 1024\n",
    "setup_geometry.toml": "[setup]\nr1_ohm = 50\ninner_diameter_m = 0.016\nouter_diameter_m = 0.019\n"
                           'length_m = 0.02\ndensity_kg_m3 = 7600\nnotes = """two\nlines"""\n',
    "inline_tables.toml": 'excitation = { kind = "exp_decay", decay_per_s = 1.5e4 }\n'
                          "acquisition = { samples = 0x100, pretrigger_samples = 0o10, shots = 1_0 }\n",
    "empty.toml": "",
}

# ---------------------------------------------------------------- impedance_file
def bvd(f):
    """Z of a BVD resonator: C0 parallel with R-L-C (resonance ~ 50 kHz)."""
    w = 2 * math.pi * f
    c0, r, l, c = 2e-9, 40.0, 0.05, 2.026e-10
    ym = 1 / (r + 1j * w * l + 1 / (1j * w * c))
    return 1 / (1j * w * c0 + ym)


freqs = [1000.0 * k for k in range(1, 101)]  # 1..100 kHz: resonance 50 kHz, anti-resonance 52.5 kHz
csv = "f_hz,re_ohm,im_ohm\n# BVD resonator\n" + "".join(
    f"{f:.6g},{bvd(f).real:.9g},{bvd(f).imag:.9g}\n" for f in freqs)
csv_band = "f_hz,re_ohm,im_ohm,re_lo,re_hi\n" + "".join(
    f"{f:.6g},{bvd(f).real:.9g},{bvd(f).imag:.9g},0,0\r\n" for f in freqs[::3])


def s11(z, z0=50.0):
    return (z - z0) / (z + z0)


ts_z_ri = "! Touchstone 1.0, one port\n# Hz Z RI R 1\n" + "".join(
    f"{f:.6g} {bvd(f).real:.9g} {bvd(f).imag:.9g}\n" for f in freqs[::2])
ts_s_ma = "# kHz S MA R 50\n" + "".join(
    f"{f / 1e3:.6g} {abs(s11(bvd(f))):.9g} {math.degrees(cmath.phase(s11(bvd(f)))):.9g} ! point\n"
    for f in freqs[::2])
ts_s_db = "!comment\n  # MHz S DB R 75\n" + "".join(
    f"  {f / 1e6:.9g}\t{20 * math.log10(abs(s11(bvd(f), 75))):.9g}  "
    f"{math.degrees(cmath.phase(s11(bvd(f), 75))):.9g}\n" for f in freqs[::4])
impedance = {
    "bvd.csv": csv,
    "bvd_band.csv": csv_band,
    "bvd_z_ri.s1p": ts_z_ri,
    "bvd_s_ma.s1p": ts_s_ma,
    "bvd_s_db.s1p": ts_s_db,
    "minimal.csv": "1,1,-1\n2,1,-0.5\n3,1,-0.3\n4,1,-0.2\n5,1,-0.1\n",
}

# ---------------------------------------------------------------- impedance file readers
# Seeds of fuzz_touchstone, fuzz_hp4294a, fuzz_e4990a, fuzz_bode100 and
# fuzz_impedance_table, fuzz_hioki, fuzz_labone and fuzz_impedance_columns
# (dsp/impedance_files/): the BVD above in each format,
# 10-20 points each (under libFuzzer's 4 KB), plus a cut of a real 4294A file.
few = [40000.0 + 1000.0 * k for k in range(0, 21, 2)]  # 40..60 kHz, resonance at 50 kHz


def ts_value(z, param, form, r, v2):
    x = (z - r) / (z + r) if param == "S" else z if param == "Z" else 1 / z
    if not v2 and param == "Z":
        x /= r
    if not v2 and param == "Y":
        x *= r
    if form == "RI":
        return f"{x.real:.9g} {x.imag:.9g}"
    mag = abs(x) if form == "MA" else 20 * math.log10(abs(x))
    return f"{mag:.9g} {math.degrees(cmath.phase(x)):.9g}"


touchstone = {
    "v1_s_ma.s1p": "! VNA one port\n# kHz S MA R 50\n" + "".join(
        f"{f / 1e3:.6g} {ts_value(bvd(f), 'S', 'MA', 50, False)}\n" for f in few),
    "v1_y_db.s1p": "# Hz Y DB R 75 ! normalized admittance\n" + "".join(
        f"{f:.6g}\t{ts_value(bvd(f), 'Y', 'DB', 75, False)}\n" for f in few),
    "v1_z_ri.s1p": "# MHz Z RI R 1\n" + "".join(
        f"  {f / 1e6:.9g}  {ts_value(bvd(f), 'Z', 'RI', 1, False)}\n" for f in few),
    "v2_s_db.ts": f"[Version] 2.0\n# GHz S DB R 50\n[Number of Ports] 1\n[Number of Frequencies] {len(few)}\n"
                  "[Reference]\n75\n[Begin Information]\nanything\n[End Information]\n[Network Data]\n" + "".join(
        f"{f / 1e9:.9g} {ts_value(bvd(f), 'S', 'DB', 75, True)}\n" for f in few) + "[End]\n",
    "v2_y_ri.ts": f"[Version] 2.0\n# Hz Y RI R 50\n[Number of Ports] 1\n[Two-Port Data Order] 12_21\n"
                  f"[Number of Frequencies] {len(few)}\n[Matrix Format] Full\n[Network Data]\n" + "".join(
        f"{f:.9g}\n  {ts_value(bvd(f), 'Y', 'RI', 50, True)} ! split\n" for f in few) + "[End]\n",
    "no_option.s1p": "".join(f"{f / 1e9:.6g} {ts_value(bvd(f), 'S', 'MA', 50, False)}\n" for f in few[:5]),
}


def hp4294a(parameter, first, second, memory=False, n=None):
    fs = few if n is None else few[:n]
    s = (f'4294A REV1.11\n"DATE:     52 -100"\n\n\n"MEASURE PARAMETER: {parameter}"\n"ADAPTER: 7mm"\n'
         f'"SWEEP TYPE: LOG FREQ"\n"NUMBER of POINTS: {len(fs)}"\n"BW: 5"\n\n\n')
    for name, value in (("A", first), ("B", second)):
        s += f'"TRACE: {name}"\n"FORMAT: LOG"\n\n"Frequency"\t"Data Trace Real"\t"Data Trace Imag"'
        s += '\t"Memory Trace Real"\t"Memory Trace Imag"\n' if memory else "\n"
        for f in fs:
            s += f"{f:.11e}\t{value(f, bvd(f)):.6e}\t{0.0:.6e}"
            s += f"\t{1.0:.6e}\t{0.0:.6e}\n" if memory else "\n"
        s += "\n\n"
    return s


def real_cut(path, rows):
    """The settings of a real 4294A file and its first rows of each trace."""
    out, kept, trace = [], 0, None
    for line in open(path).read().split("\n"):
        if line.startswith('"NUMBER of POINTS'):
            line = f'"NUMBER of POINTS: {rows}"'
        if line.startswith('"TRACE:'):
            trace, kept = line, 0
        if trace and line[:1].isdigit():
            kept += 1
            if kept > rows:
                continue
        out.append(line)
    return "\n".join(out)


FIXTURES = os.path.join(HERE, "..", "..", "fixtures", "eqcirc3")
hp4294a_files = {
    "z_mag_phase.txt": hp4294a("IMPEDANCE MAG PHASE (DEG)", lambda f, z: abs(z),
                               lambda f, z: math.degrees(cmath.phase(z))),
    "y_mag_phase_memory.txt": hp4294a("ADMITTANCE MAG PHASE (DEG)", lambda f, z: 1 / abs(z),
                                      lambda f, z: -math.degrees(cmath.phase(z)), memory=True),
    "r_x.txt": hp4294a("R-X", lambda f, z: z.real, lambda f, z: z.imag, n=6),
    "cp_d.txt": hp4294a("CP-D", lambda f, z: (1 / z).imag / (2 * math.pi * f),
                        lambda f, z: (1 / z).real / abs((1 / z).imag), n=6),
    "md1_cut.txt": real_cut(os.path.join(FIXTURES, "MD1.txt"), 8),
    "rb5100_cut.txt": real_cut(os.path.join(FIXTURES, "RB5100.txt"), 6),
}


def e4990a(header, row, instrument="!Agilent Technologies,E4990A,MY521012345,A.02.10\n", extra=""):
    s = instrument + "!Date: Fri Apr 03 13:41:16 2015\nBEGIN CH1_DATA\n" + extra + header + "\n"
    s += "".join(row(f, bvd(f)) + "\n" for f in few) + "END\n"
    return s


e4990a_files = {
    "z_theta.csv": e4990a("Frequency(Hz), |Z|(Ohm)-data, theta-z(deg)-data, theta-z(deg)-mem",
                          lambda f, z: f"{f:+.11e}, {abs(z):+.11e}, {math.degrees(cmath.phase(z)):+.11e}, +1.0e+000",
                          extra="Title label, TEST DATA\nDCV(V), +5.230e-005, DCI(A), +2.335e-005\n")
                   + "BEGIN CH2_DATA\nFrequency(Hz), Z-Real(Ohm)-data, Z-Imag(Ohm)-data\n+1e+006, +1, +2\nEND\n",
    "r_x.csv": e4990a("Frequency(Hz), R(Ohm)-data, X(Ohm)-data",
                      lambda f, z: f"{f:+.11e}, {z.real:+.11e}, {z.imag:+.11e}"),
    "cp_d.csv": e4990a("Frequency(Hz), Cp(F)-data, D()-data",
                       lambda f, z: f"{f:+.6e}, {(1 / z).imag / (2 * math.pi * f):+.6e}, "
                                    f"{(1 / z).real / abs((1 / z).imag):+.6e}"),
    "decimal_comma.csv": e4990a("Frequency(Hz), |Z|(Ohm)-data, theta-z(deg)-data",
                                lambda f, z: f"{f:+.6e},{abs(z):+.6e},{math.degrees(cmath.phase(z)):+.6e}".replace(".", ",")),
    "pna_s11.csv": e4990a("Freq(Hz),S11(REAL),S11(IMAG)",
                          lambda f, z: f"{f:.9g},{s11(bvd(f)).real:.9g},{s11(bvd(f)).imag:.9g}",
                          instrument="!CSV A.01.01\n!Keysight Technologies,E5061B,MY1,A.03\n"),
}

OHM, DEG = "\u2126", "\u00b0"
bode100 = {
    "real_imag.csv": ("\ufeffFrequency (Hz);Trace 1: Impedance: Real (" + OHM + ");Trace 1: Impedance: Imaginary ("
                      + OHM + ");Trace 1: Impedance: Real (" + OHM + ")\r\n" + "".join(
                          f"{f:.10g};{bvd(f).real:.15g};{bvd(f).imag:.15g};{bvd(f).real:.15g}\r\n" for f in few) + "\r\n"),
    "mag_phase_comma.csv": ("Frequency (Hz);Trace 1: Impedance: Magnitude (\u03a9);Trace 2: Impedance: Phase (" + DEG
                            + ")\n" + "".join(f"{f:.10g};{abs(bvd(f)):.12g};{math.degrees(cmath.phase(bvd(f))):.12g}\n"
                                              .replace(".", ",") for f in few)),
    "admittance.csv": ("Frequency (Hz),Trace 1: Admittance: Magnitude (S),Trace 2: Admittance: Phase (" + DEG + ")\n"
                       + "".join(f"{f:.10g},{1 / abs(bvd(f)):.12g},{-math.degrees(cmath.phase(bvd(f))):.12g}\n"
                                 for f in few)),
    "gain.csv": "Frequency (Hz);Trace 1: Gain: Magnitude (dB);Trace 1: Gain: Phase (" + DEG + ")\n1000;-3;45\n2000;-6;60\n",
}

table = {
    "f_re_im.csv": "f_hz,re_ohm,im_ohm\n" + "".join(f"{f:.10g},{bvd(f).real:.10g},{bvd(f).imag:.10g}\n" for f in few),
    "band.csv": "f_hz,re_ohm,im_ohm,abs_ohm,abs_sigma_ohm,phase_deg,phase_sigma_deg,coverage_factor\n" + "".join(
        f"{f:.10g},{bvd(f).real:.10g},{bvd(f).imag:.10g},{abs(bvd(f)):.10g},{abs(bvd(f)) * 1e-3:.6g},"
        f"{math.degrees(cmath.phase(bvd(f))):.8g},0.05,1.96\n" for f in few[:6]),
    "khz_kohm_deg.csv": "Frequency (kHz),|Z| (kOhm),Phase (deg)\n" + "".join(
        f"{f / 1e3:.9g},{abs(bvd(f)) / 1e3:.9g},{math.degrees(cmath.phase(bvd(f))):.9g}\n" for f in few),
    "g_b_tab.tsv": "f [MHz]\tG [mS]\tB [mS]\n" + "".join(
        f"{f / 1e6:.9g}\t{(1 / bvd(f)).real * 1e3:.9g}\t{(1 / bvd(f)).imag * 1e3:.9g}\n" for f in few),
    "spaces_rad.txt": "# sweep\nFrequency (Hz)   |Y| (uS)   Phase (rad)\n" + "".join(
        f"{f:.9g}   {1e6 / abs(bvd(f)):.9g}   {-cmath.phase(bvd(f)):.9g}\n" for f in few),
    "semicolon_comma.csv": "freq;R (Ohm);X (Ohm)\n" + "".join(
        f"{f:.9g};{bvd(f).real:.9g};{bvd(f).imag:.9g}\n".replace(".", ",") for f in few),
    "db.csv": "f_hz,Z_dB,phase_deg\n" + "".join(
        f"{f:.9g},{20 * math.log10(abs(bvd(f))):.9g},{math.degrees(cmath.phase(bvd(f))):.9g}\n" for f in few),
    "comment_header.csv": "! CMT S2VNA\n! Stimulus(Hz), Re(S11), Im(S11)\n" + "".join(
        f"{f:.9g}, {s11(bvd(f)).real:.9g}, {s11(bvd(f)).imag:.9g}\n" for f in few[:5]),
    "headerless.csv": "1,1,-1\n2,1,-0.5\n3,1,-0.3\n",
}


# Issue 39: HIOKI IM3570 CSV (Shift-JIS units, quoted fields, CR LF), LabOne
# exports, two-port Touchstone, and --columns (first line: the column spec).
OHM_SJIS, THETA_SJIS, DEG_SJIS = b"\x83\xb6", b"\x83\xc6", b"\x81\x8b"


def eng(v):
    if v == 0:
        return "0.0000E+00"
    e = int(math.floor(math.log10(abs(v)) / 3)) * 3
    return f"{v / 10 ** e:.4f}E{e:+03d}"


def hioki(p1, p2, value1, value2):
    s = (b'"MODEL","IM3570"\r\n"VERSION","V2.10"\r\n"MODE","ANALYZER"\r\n'
         b'"\x91\xaa\x92\xe8","LCR"\r\n"No.","FREQUENCY(Hz)","' + p1 + b'","' + p2 + b'"\r\n')
    for k, f in enumerate(few):
        z = bvd(f)
        s += (f'"{k + 1}","{eng(f)}","{value1(f, z)}","{value2(f, z)}"\r\n').encode()
    return s


hioki_files = {
    "z_x.csv": hioki(b"Z[" + OHM_SJIS + b"]", b"X[" + OHM_SJIS + b"]",
                     lambda f, z: eng(abs(z)), lambda f, z: eng(z.imag)),
    "z_theta.csv": hioki(b"Z[" + OHM_SJIS + b"]", THETA_SJIS + b"[" + DEG_SJIS + b"]",
                         lambda f, z: eng(abs(z)), lambda f, z: eng(math.degrees(cmath.phase(z)))),
    "cs_d.csv": hioki(b"Cs[F]", b"D[]", lambda f, z: eng(-1 / (2 * math.pi * f * z.imag)),
                      lambda f, z: eng(z.real / abs(z.imag))),
    "g_b.csv": hioki(b"G[S]", b"B[S]", lambda f, z: eng((1 / z).real), lambda f, z: eng((1 / z).imag)),
    "z_off.csv": hioki(b"Z[" + OHM_SJIS + b"]", b"OFF", lambda f, z: eng(abs(z)), lambda f, z: ""),
    "g_off.csv": hioki(b"G[S]", b"OFF", lambda f, z: eng((1 / z).real), lambda f, z: ""),
}

labone = {
    "sweeper.csv": "chunk;timestamp;grid;frequency;realz;imagz;absz;phasez;param0;param1\n" + "".join(
        f"{c};{123456789 + 1000 * k};{f:.9g};{f:.9g};{bvd(f).real:.9g};{bvd(f).imag:.9g};{abs(bvd(f)):.9g};"
        f"{cmath.phase(bvd(f)):.9g};1e-9;0.01\n" for c in (0, 1) for k, f in enumerate(few[:6])),
    "text.txt": "% Zurich Instruments LabOne sweeper export\n% frequency absz phasez\n" + "".join(
        f"{f:.9g} {abs(bvd(f)):.9g} {cmath.phase(bvd(f)):.9g}\n" for f in few) + "61000 nan nan\n",
    "representation.csv": "% representation: Cp D\nfrequency;param0;param1\n" + "".join(
        f"{f:.9g};{(1 / bvd(f)).imag / (2 * math.pi * f):.9g};{(1 / bvd(f)).real / abs((1 / bvd(f)).imag):.9g}\n"
        for f in few),
    "demod.csv": "chunk;timestamp;grid;frequency;x;y;r;phase\n0;1;1000;1000;0.1;0.2;0.22;1.1\n",
    "transposed.csv": "chunk;timestamp;size;fieldname" + ";" * 6 + "\n" + "".join(
        f"{c};{1000 + c};6;{name};" + ";".join(
            "nan" if c == 2 and k < 2 else f"{value(few[k]):.9g}" for k in reversed(range(6))) + "\n"
        for c in range(3)
        for name, value in (("absz", lambda f: abs(bvd(f))), ("frequency", lambda f: f),
                            ("imagz", lambda f: bvd(f).imag), ("realz", lambda f: bvd(f).real))),
}


def s2p_line(f, z):
    a, b = z / (z + 100), 100 / (z + 100)  # a device in series between two 50-ohm ports
    return f"{f:.9g} {a.real:.9g} {a.imag:.9g} {b.real:.9g} {b.imag:.9g} {b.real:.9g} {b.imag:.9g} " \
           f"{a.real:.9g} {a.imag:.9g}\n"


touchstone["series_through.s2p"] = "! N5230A\n# Hz S RI R 50\n" + "".join(s2p_line(f, bvd(f)) for f in few)
touchstone["v2_two_port.s2p"] = (f"[Version] 2.0\n# Hz S RI R 50\n[Number of Ports] 2\n[Two-Port Data Order] 21_12\n"
                                 f"[Number of Frequencies] {len(few[:6])}\n[Reference] 50 50\n[Network Data]\n"
                                 + "".join(s2p_line(f, bvd(f)) for f in few[:6]) + "[End]\n")

columns = {
    "g_b_khz_us.txt": "f[kHz],G[uS],B[uS],-\n" + "".join(
        f"{f / 1e3:.9g}\t{(1 / bvd(f)).real * 1e6:.9g}\t{(1 / bvd(f)).imag * 1e6:.9g}\t7\n" for f in few),
    "z_theta.txt": "f,|Z|,theta(deg),skip,skip\n" + "".join(
        f"{f:.9g} {abs(bvd(f)):.9g} {math.degrees(cmath.phase(bvd(f))):.9g} 1 2\n" for f in few),
    "z_only_header.csv": "f[Hz],|Z|[ohm]\nfreq,mag\n" + "".join(f"{f:.9g},{abs(bvd(f)):.9g}\n" for f in few),
    "cp_d.csv": "f[Hz],Cp[nF],D\n" + "".join(
        f"{f:.9g};{(1 / bvd(f)).imag / (2 * math.pi * f) * 1e9:.9g};{(1 / bvd(f)).real / abs((1 / bvd(f)).imag):.9g}\n"
        .replace(".", ",") for f in few),
}
table["s11_s21.csv"] = "Freq(Hz),S11(DB),S11(DEG),S21(DB),S21(DEG)\n" + "".join(
    f"{f:.9g},{20 * math.log10(abs(bvd(f) / (bvd(f) + 100))):.9g},{math.degrees(cmath.phase(bvd(f) / (bvd(f) + 100))):.9g},"
    f"{20 * math.log10(abs(100 / (bvd(f) + 100))):.9g},{math.degrees(cmath.phase(100 / (bvd(f) + 100))):.9g}\n" for f in few)
table["z_x.csv"] = "f (kHz),|Z| (Ohm),X (Ohm)\n" + "".join(f"{f / 1e3:.9g},{abs(bvd(f)):.9g},{bvd(f).imag:.9g}\n" for f in few)
table["repeated_f.txt"] = " Frequency      Resistance       Reactance\r\r\n\r\n" + "".join(
    f"   {f:.6E}    {bvd(f).real:.6E}    {bvd(f).imag:.6E}\r\r\n" for f in [few[0]] + few)


# ---------------------------------------------------------------- capture
def recipes():
    rng = random.Random(16)
    out = {"empty": b"", "three_shots_sparse": bytes([0] * 40 + [2] + [0] * 200)}
    for k in range(8):  # mostly zero: mostly valid captures with a few odd choices
        n = rng.choice([128, 256, 512, 1024])
        b = bytearray(n)
        for _ in range(rng.randrange(2, n // 16)):
            b[rng.randrange(n)] = rng.randrange(256)
        out[f"sparse_{k}"] = bytes(b)
    for k in range(4):  # every decision random: mostly refused files
        out[f"dense_{k}"] = bytes(rng.randrange(256) for _ in range(rng.choice([64, 256, 1024])))
    return out


def main():
    for name, data in block.items():
        write("block_parser", name, data)
    for name, data in plans.items():
        write("plan", name, data)
    for name, data in impedance.items():
        write("impedance_file", name, data)
    for name, data in recipes().items():
        write("capture", name, data)
    for harness, files in (("touchstone", touchstone), ("hp4294a", hp4294a_files), ("e4990a", e4990a_files),
                           ("bode100", bode100), ("impedance_table", table), ("hioki", hioki_files),
                           ("labone", labone), ("impedance_columns", columns)):
        for name, data in files.items():
            write(harness, name, data)


if __name__ == "__main__":
    main()
