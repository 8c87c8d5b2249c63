#!/usr/bin/python3
"""Reference measurement of what a real impedance file shows (issue 39, item 1).

Usage:  real-file-features.py FILE [--json] [--s2p-mode series|shunt|s11]
                                [--columns f[kHz],G[S],B[S]]
  --columns names the columns of a headerless table, e.g. f,|Z|,-theta[deg],skip
  ('skip' ignores a column; a leading '-' flips its sign).

Independent of the C++ readers: a small numpy-only reader for the layouts found
in the real-file corpus (Touchstone s1p/s2p; Keysight E4990A / Agilent 4294A CSV
and text; HIOKI CSV; Zurich Instruments LabOne CSV; OMICRON Bode CSV; plain
headed or headerless tables with ',', ';' or tab, decimal commas, BOM,
Shift-JIS), then the features:

  conductance_peaks_hz  local maxima of G = Re(1/Z)      (rule below)
  r_max_hz              local maxima of R = Re(Z)         (rule below)
  z_min_hz / z_max_hz   local minima / maxima of |Z|      (rule below, on log|Z|)
  c_lowf_f              C = -1/(2 pi f Im Z), mean of the 3 lowest-frequency
                        points, only where the phase there is between -95 and
                        -45 degrees (capacitive); else null

Peak rule (scipy-free): a local maximum of y (on the points as sampled) is kept
when its topographic prominence (height above the higher of the two lowest
points between it and the nearest higher point on either side, or the sweep
ends) is at least 10 % of the peak's own height above the sweep minimum, at
least 1 % of the sweep's range of y, and at least 5 times the point-to-point
noise (1.4826 * MAD of the second difference of y / sqrt(6), taken over the
101 points centred on the peak, so that a noisy stretch does not make peaks).  For |Z| the rule
runs on log10|Z| (and on -log10|Z| for minima) with the 10 % replaced by 0.02
decades.  At most 25 peaks are listed, by frequency.
"""
import io
import json
import math
import re
import sys

import numpy as np

G_ONLY = []   # set by z_from_cols when a table holds conductance alone
UNIT = {'HZ': 1.0, 'KHZ': 1e3, 'MHZ': 1e6, 'GHZ': 1e9}


def decode(raw):
    if raw.startswith(b'\xef\xbb\xbf'):
        return raw[3:].decode('utf-8'), 'utf-8 with BOM'
    if raw.startswith(b'\xff\xfe') or raw.startswith(b'\xfe\xff'):
        return raw.decode('utf-16'), 'utf-16 with BOM'
    try:
        return raw.decode('utf-8'), ('ascii' if max(raw, default=0) < 128 else 'utf-8')
    except UnicodeDecodeError:
        pass
    try:
        return raw.decode('shift_jis'), 'shift-jis'
    except UnicodeDecodeError:
        return raw.decode('latin-1'), 'latin-1'


def num(tok):
    tok = tok.strip().strip('"').strip()
    if tok == '':
        return None
    try:
        return float(tok)
    except ValueError:
        pass
    if re.fullmatch(r'[+-]?\d+,\d*([eE][+-]?\d+)?', tok):
        return float(tok.replace(',', '.'))
    return None


# ---------------------------------------------------------------- touchstone
def read_touchstone(text, name, s2p_mode):
    unit, fmt, z0 = 1e9, 'MA', 50.0
    vals = []
    for line in text.splitlines():
        line = line.split('!', 1)[0].strip()
        if not line:
            continue
        if line.startswith('#'):
            t = line[1:].upper().split()
            for i, w in enumerate(t):
                if w in UNIT:
                    unit = UNIT[w]
                elif w in ('RI', 'MA', 'DB'):
                    fmt = w
                elif w == 'R' and i + 1 < len(t):
                    z0 = float(t[i + 1])
            continue
        if line.startswith('['):
            continue
        vals.extend(float(x) for x in line.split())
    nport = 2 if name.lower().endswith('.s2p') else 1
    width = 1 + 2 * nport * nport
    a = np.array(vals[: len(vals) // width * width]).reshape(-1, width)
    f = a[:, 0] * unit

    def cplx(c):
        x, y = a[:, c], a[:, c + 1]
        if fmt == 'RI':
            return x + 1j * y
        mag = x if fmt == 'MA' else 10 ** (x / 20)
        return mag * np.exp(1j * np.deg2rad(y))

    note = 'touchstone %s, Z0=%g, unit %g Hz' % (fmt, z0, unit)
    if nport == 1 or s2p_mode == 's11':
        s11 = cplx(1)
        return f, z0 * (1 + s11) / (1 - s11), note + ', Z from S11 (reflection)'
    s21 = cplx(3)
    if s2p_mode == 'shunt':
        return f, z0 * s21 / (2 * (1 - s21)), note + ', Z shunt-through from S21'
    return f, 2 * z0 * (1 - s21) / s21, note + ', Z series-through from S21'


# --------------------------------------------------------------------- tables
def split_line(line, sep):
    if sep is None:
        return line.split()
    out, cur, q = [], '', False
    for ch in line:
        if ch == '"':
            q = not q
            continue
        if ch == sep and not q:
            out.append(cur)
            cur = ''
        else:
            cur += ch
    out.append(cur)
    return out


def guess_sep(lines):
    best, score = None, 0
    for sep in ['\t', ';', ',']:
        counts = [len(split_line(l, sep)) for l in lines[-20:] if l.strip()]
        if counts and min(counts) >= 2 and min(counts) == max(counts):
            if counts[0] > score:
                best, score = sep, counts[0]
    return best


def colkind(h):
    """Map a header cell to (kind, scale). kinds: f, zmag, phase_deg, phase_rad,
    r, x, g, b, re_y, im_y, cs, d, ..."""
    s = h.strip().strip('"').strip()
    if s.startswith('-') and len(s) > 1 and not s[1].isdigit():
        # '--columns' spec: a leading '-' flips the sign (e.g. '-theta[deg]' for a
        # file that stores the phase of the current, not of Z)
        kind, scale = colkind(s[1:])
        return kind, -scale
    low = s.lower().replace(' ', '')
    scale = 1.0
    m = re.search(r'[\[(]\s*([a-zA-Zµμ°Ωω]*)\s*[\])]', s)
    u = (m.group(1) if m else '').replace('μ', 'µ')
    pre = {'k': 1e3, 'M': 1e6, 'G': 1e9, 'm': 1e-3, 'u': 1e-6, 'µ': 1e-6, 'n': 1e-9, 'p': 1e-12}
    low = re.sub(r'^tr\d+:', '', low)          # OMICRON Bode Analyzer Suite trace prefix
    if 'impedance(real)' in low:
        return 'r', 1.0
    if 'impedance(imag' in low:
        return 'x', 1.0
    if 'impedance(absolut' in low or 'impedance(magnitude)' in low:
        return 'zmag', 1.0
    if 'gain' in low:
        return None, 1.0
    if low.startswith('transmissionloss') or low.startswith('s21(db)'):
        return 's21_db', 1.0
    if low.startswith('s11(db)') or low.startswith('s11db'):
        return 's11_db', 1.0
    if low.startswith('s11(deg)') or low.startswith('s11deg'):
        return 's11_deg', 1.0
    if low.startswith('freq') or low in ('f', 'f(hz)', 'hz', 'frequency') or low.startswith('f['):
        if u and u[0] in pre and u.lower().endswith('hz'):
            scale = pre[u[0]]
        return 'f', scale
    if u and len(u) >= 2 and u[0] in pre and u[1:] in ('S', 'Ω', 'Ohm', 'ohm', 'F', 'H'):
        scale = pre[u[0]]
    if 'deg' in low or '°' in s:
        if 'phase' in low or 'theta' in low or 'θ' in s or 'phi' in low:
            return 'phase_deg', 1.0
    if ('phase' in low or 'theta' in low or 'θ' in s) and 'rad' in low:
        return 'phase_rad', 1.0
    if 'theta' in low or 'θ' in s or low.startswith('phase'):
        return 'phase_deg', 1.0
    if low.startswith('|z|') or low.startswith('z[') or low.startswith('z(') or low in ('z', '|z|') \
            or 'impedancemagnitude' in low or low.startswith('abs(z)') or low.startswith('absz') \
            or low.startswith('zmag') or low.startswith('magz') or low.startswith('impedance('):
        return 'zmag', scale
    if low.startswith('realz') or low.startswith('re(z)') or low.startswith('rez') or low.startswith('r[') \
            or low.startswith('r(') or low in ('r', 'rs', 'rs(ohm)', 'rs(ω)') or low.startswith('resistance') or low.startswith('rs[') \
            or low.startswith('z\'') or low.startswith('zre') or low.startswith('z_re') or low.startswith('z.real'):
        return 'r', scale
    if low.startswith('imagz') or low.startswith('im(z)') or low.startswith('imz') or low.startswith('x[') \
            or low.startswith('x(') or low in ('x', 'xs', 'xs(ohm)', 'xs(ω)') or low.startswith('reactance') \
            or low.startswith('z\'\'') or low.startswith('zim') or low.startswith('z_im') or low.startswith('z.imag'):
        return 'x', scale
    if low.startswith('g[') or low.startswith('g(') or low == 'g' or low.startswith('conductance'):
        return 'g', scale
    if low.startswith('b[') or low.startswith('b(') or low == 'b' or low.startswith('susceptance'):
        return 'b', scale
    return None, 1.0


def z_from_cols(cols, data):
    k = {}
    for i, c in enumerate(cols):      # the first column of each kind wins
        if c[0] and c[0] not in k:
            k[c[0]] = (i, c[1])
    if 'f' not in k:
        return None, None, 'no frequency column'
    fi, fs = k['f']
    f = data[:, fi] * fs
    get = lambda n: data[:, k[n][0]] * k[n][1]
    if 's21_db' in k and 'phase_deg' in k:
        # vna/J transmission export: its own Rs/Xs columns are this same
        # series-through Z, but printed in a fixed width that drops digits
        s21 = 10 ** (get('s21_db') / 20) * np.exp(1j * np.deg2rad(get('phase_deg')))
        return f, 2 * 50.0 * (1 - s21) / s21, 'S21 dB/deg -> series-through Z (Z0 50 ohm, transmission)'
    if 'r' in k and 'x' in k:
        return f, get('r') + 1j * get('x'), 'R,X'
    if 's11_db' in k and 's11_deg' in k:
        s11 = 10 ** (get('s11_db') / 20) * np.exp(1j * np.deg2rad(get('s11_deg')))
        return f, 50.0 * (1 + s11) / (1 - s11), 'S11 dB/deg -> Z (Z0 50 ohm, reflection)'
    if 'zmag' in k and 'phase_deg' in k:
        return f, get('zmag') * np.exp(1j * np.deg2rad(get('phase_deg'))), '|Z|,theta[deg]'
    if 'zmag' in k and 'phase_rad' in k:
        return f, get('zmag') * np.exp(1j * get('phase_rad')), '|Z|,theta[rad]'
    if 'zmag' in k and 'x' in k:
        zm, x = get('zmag'), get('x')
        r = np.sqrt(np.maximum(zm ** 2 - x ** 2, 0))
        return f, r + 1j * x, '|Z|,X (R>=0 assumed)'
    if 'g' in k and 'b' in k:
        return f, 1 / (get('g') + 1j * get('b')), 'G,B'
    if 'zmag' in k:
        return f, get('zmag').astype(complex), '|Z| only (no phase)'
    if 'g' in k:
        G_ONLY.append(get('g'))
        return f, None, 'conductance only: no complex Z and no |Z| (a reader must refuse)'
    return f, None, 'no impedance columns among %s' % [c for c in k]


def read_table(text, colspec=None):
    lines = [l.rstrip('\r') for l in text.splitlines()]
    # E4990A / 4294A style: BEGIN ... END blocks with '!' comments
    body = []
    in_block = None
    for l in lines:
        s = l.strip()
        if s.upper().startswith('BEGIN'):
            in_block = True
            continue
        if s.upper() == 'END':
            if in_block:
                break
            continue
        body.append(l)
    data_lines, header = [], None
    sep = guess_sep([l for l in body if l.strip() and not l.lstrip().startswith(('!', '%', '#'))])
    for l in body:
        s = l.strip()
        if not s or s.startswith('!') or s.startswith('#'):
            continue
        if s.startswith('%'):
            # LabOne: '% a; b; c' header lines; keep last as possible header
            cand = s.lstrip('%').strip()
            if sep and cand.count(sep) >= 1:
                header = split_line(cand, sep)
            continue
        toks = split_line(s, sep)
        vals = [num(t) for t in toks]
        if sum(v is not None for v in vals) >= 2 and vals[0] is not None:
            data_lines.append(vals)
        elif not data_lines:
            header = toks
    if not data_lines:
        return None, None, 'no numeric rows', sep
    width = max(len(r) for r in data_lines)
    arr = np.array([[np.nan if (i >= len(r) or r[i] is None) else r[i] for i in range(width)]
                    for r in data_lines])
    if colspec:
        cols = [colkind(c) for c in colspec.split(',')]
        hdr = colspec
    elif header:
        cols = [colkind(h) for h in header]
        hdr = header
    else:
        return None, None, 'headerless table: give --columns', sep
    f, z, how = z_from_cols(cols, arr)
    if f is not None and z is not None:
        good = np.isfinite(f) & np.isfinite(z)
        f, z = f[good], z[good]
        o = np.argsort(f)
        f, z = f[o], z[o]
    return f, z, 'columns %s -> %s' % (hdr, how), sep


# --------------------------------------------------------------------- peaks
def noise(y):
    if len(y) < 5:
        return 0.0
    d2 = np.diff(y, 2)
    return 1.4826 * np.median(np.abs(d2 - np.median(d2))) / math.sqrt(6)


def prominences(y):
    n = len(y)
    out = []
    for i in range(1, n - 1):
        if not (y[i] > y[i - 1] and y[i] >= y[i + 1]):
            continue
        j = i - 1
        lmin = y[i]
        while j >= 0 and y[j] <= y[i]:
            lmin = min(lmin, y[j])
            j -= 1
        k = i + 1
        rmin = y[i]
        while k < n and y[k] <= y[i]:
            rmin = min(rmin, y[k])
            k += 1
        out.append((i, y[i] - max(lmin, rmin)))
    return out


def local_noise(y, i, half=50):
    a, b = max(0, i - half), min(len(y), i + half + 1)
    if b - a < 7:
        a, b = max(0, b - 7), min(len(y), a + 7)
    return noise(y[a:b])


def peaks(f, y, rel=0.10, log=False, maxn=25):
    y = np.asarray(y, float)
    ok = np.isfinite(y)
    f, y = f[ok], y[ok]
    if len(y) < 5:
        return []
    rng = y.max() - y.min()
    keep = []
    for i, p in prominences(y):
        nz = local_noise(y, i)
        if log:
            if p < max(0.02, 0.01 * rng, 5 * nz):
                continue
        else:
            if p < max(rel * (y[i] - y.min()), 0.01 * rng, 5 * nz):
                continue
        keep.append((p, i))
    keep.sort(reverse=True)
    keep = sorted(keep[:maxn], key=lambda t: t[1])
    return [float('%.6g' % f[i]) for _, i in keep]


def features(f, z):
    res = {'f_min_hz': float('%.6g' % f[0]), 'f_max_hz': float('%.6g' % f[-1]), 'points': int(len(f))}
    if np.all(np.abs(np.imag(z)) == 0) and np.all(np.real(z) >= 0):
        # |Z| only
        res['conductance_peaks_hz'] = None
        res['r_max_hz'] = None
        res['c_lowf_f'] = None
        zl = np.log10(np.abs(z))
        res['z_min_hz'] = peaks(f, -zl, log=True)
        res['z_max_hz'] = peaks(f, zl, log=True)
        return res
    y = 1 / z
    res['conductance_peaks_hz'] = peaks(f, y.real)
    res['r_max_hz'] = peaks(f, z.real)
    zl = np.log10(np.abs(z))
    res['z_min_hz'] = peaks(f, -zl, log=True)
    res['z_max_hz'] = peaks(f, zl, log=True)
    ph = np.rad2deg(np.angle(z[:3]))
    if np.all((ph < -45) & (ph > -95)):
        c = -1 / (2 * np.pi * f[:3] * z[:3].imag)
        res['c_lowf_f'] = float('%.4g' % np.mean(c))
    else:
        res['c_lowf_f'] = None
    res['phase_lowf_deg'] = float('%.4g' % np.mean(ph))
    return res


def read_4294a(text):
    """Agilent 4294A 'ASCII' save: quoted preamble, one block per trace
    ('"TRACE: A"', '"FORMAT: ..."', a quoted column header, then
    frequency, real, imag rows, tab separated)."""
    lines = [l.rstrip('\r') for l in text.splitlines()]
    param = ''
    traces, cur = {}, None
    for l in lines:
        s = l.strip()
        if s.startswith('"MEASURE PARAMETER:'):
            param = s.strip('"').split(':', 1)[1].strip().upper()
        elif s.startswith('"TRACE:'):
            cur = s.strip('"').split(':', 1)[1].strip()
            traces[cur] = []
        elif cur and s and not s.startswith('"'):
            v = [num(t) for t in s.split()]
            if len(v) >= 3 and None not in v[:3]:
                traces[cur].append(v[:3])
    a = np.array(traces.get('A', []))
    b = np.array(traces.get('B', [])) if traces.get('B') else None
    f = a[:, 0]
    if b is not None and len(b) == len(a):
        p, q = a[:, 1], b[:, 1]
    else:
        p, q = a[:, 1], a[:, 2]
    if 'MAG PHASE' in param:
        ph = np.deg2rad(q) if 'DEG' in param else q
        z = p * np.exp(1j * ph)
        how = '4294A %s: trace A |Z|, trace B phase' % param
    elif param.startswith('R-X') or 'R-X' in param:
        z = p + 1j * q
        how = '4294A %s' % param
    elif 'G-B' in param:
        z = 1 / (p + 1j * q)
        how = '4294A %s' % param
    elif 'COMPLEX' in param or param.startswith('IMPEDANCE') and b is None:
        z = p + 1j * q
        how = '4294A %s: complex trace' % param
    else:
        return f, None, '4294A parameter %r not handled' % param
    return f, z, how


def read_any(path, s2p_mode='series', colspec=None):
    raw = open(path, 'rb').read()
    text, enc = decode(raw)
    crlf = b'\r\n' in raw
    low = path.lower()
    if re.search(r'\.s[12]p$', low):
        f, z, how = read_touchstone(text, path, s2p_mode)
        sep = 'whitespace'
    elif '"TRACE: A"' in text[:5000] and '4294A' in text[:200]:
        f, z, how = read_4294a(text)
        sep = '\t'
    else:
        f, z, how, sep = read_table(text, colspec)
    lay = {'encoding': enc, 'line_end': 'CRLF' if crlf else 'LF',
           'separator': {None: 'whitespace', '\t': 'tab'}.get(sep, sep), 'read_as': how}
    return f, z, lay


def main():
    args = sys.argv[1:]
    js = '--json' in args
    mode = 'series'
    colspec = None
    if '--s2p-mode' in args:
        mode = args[args.index('--s2p-mode') + 1]
    if '--columns' in args:
        colspec = args[args.index('--columns') + 1]
    path = [a for a in args if not a.startswith('--') and a not in (mode, colspec)][0]
    f, z, lay = read_any(path, mode, colspec)
    if f is not None and z is None and G_ONLY:
        g = G_ONLY[-1]
        out = {'file': path, 'layout': lay, 'error': 'no impedance: conductance only',
               'f_min_hz': float('%.6g' % f.min()), 'f_max_hz': float('%.6g' % f.max()),
               'points': int(len(f)), 'conductance_peaks_hz': peaks(np.sort(f), g[np.argsort(f)])}
    elif f is None or z is None:
        out = {'file': path, 'layout': lay, 'error': 'could not read impedance'}
    else:
        out = {'file': path, 'layout': lay}
        out.update(features(f, z))
    if js:
        print(json.dumps(out))
    else:
        for k, v in out.items():
            print('%-22s %s' % (k, v))


if __name__ == '__main__':
    main()
