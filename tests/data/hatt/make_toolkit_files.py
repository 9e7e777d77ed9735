#!/usr/bin/env python3
"""Writes the two toolkit-shaped model sets in this folder (synthetic data in
the exact element layout of the Penn Haptic Texture Toolkit's files: capital
<AccelUnits>, <SpeedUnits>, <ForceUnits>, <SampleRate>, type="array" lists,
<modNum>, <ARcoeff> with a_0 = 1 first, LSFs with 6 decimals).

The AR / MA polynomials are products of pole (zero) pairs chosen here; their
LSFs are found by evaluating A(z) +- z^-(p+1) A(1/z) on the unit circle with
complex arithmetic and bisection, independently of the library's ar_to_lsf.
"""
import cmath
import math


def poly_from_pairs(pairs):
    a = [1.0]
    for r, theta in pairs:  # (1 - 2 r cos(theta) z^-1 + r^2 z^-2)
        q = [1.0, -2.0 * r * math.cos(theta), r * r]
        out = [0.0] * (len(a) + 2)
        for i, x in enumerate(a):
            for j, y in enumerate(q):
                out[i + j] += x * y
        a = out
    return a


def lsf(a):
    p = len(a) - 1
    ext = a + [0.0]
    s = [ext[k] + ext[p + 1 - k] for k in range(p + 2)]
    d = [ext[k] - ext[p + 1 - k] for k in range(p + 2)]

    def real_part(c, w, odd):  # e^{j w (p+1)/2} C(e^{jw}) is real (sum) or imaginary (difference)
        v = sum(ck * cmath.exp(-1j * w * k) for k, ck in enumerate(c)) * cmath.exp(1j * w * (p + 1) / 2)
        return v.imag if odd else v.real

    roots = []
    for c, odd in ((s, False), (d, True)):
        n = 20000
        ws = [1e-9 + (math.pi - 2e-9) * i / n for i in range(n + 1)]
        fs = [real_part(c, w, odd) for w in ws]
        for i in range(n):
            if (fs[i] < 0) != (fs[i + 1] < 0):
                lo, hi, flo = ws[i], ws[i + 1], fs[i]
                for _ in range(80):
                    m = 0.5 * (lo + hi)
                    fm = real_part(c, m, odd)
                    if (fm < 0) == (flo < 0):
                        lo, flo = m, fm
                    else:
                        hi = m
                roots.append(0.5 * (lo + hi))
    roots.sort()
    assert len(roots) == p, (len(roots), p)
    return roots


SPEEDS = [0.0, 200.0, 0.0, 200.0]
FORCES = [0.0, 0.0, 2.0, 2.0]
TRIS = [(1, 2, 3), (2, 3, 4)]  # 1-based, as MATLAB writes them


def write(path, material, rate, ar_pairs, ma_pairs, variances, gains):
    numar = 2 * len(ar_pairs[0])
    numma = 2 * len(ma_pairs[0]) if ma_pairs else 0
    out = ['<?xml version="1.0" encoding="utf-8"?>', '<modelSet texture="7">',
           f'   <material>{material}</material>', '   <AccelUnits>m/s^2</AccelUnits>',
           '   <SpeedUnits>mm/s</SpeedUnits>', '   <ForceUnits>N</ForceUnits>',
           f'   <SampleRate>{rate}</SampleRate>', '   <mu>0.412345</mu>',
           '   <htmlPicture>..\\..\\..\\TextureImages\\Synthetic_square.bmp</htmlPicture>',
           '   <htmlLinuxPicture>../../../TextureImages/Synthetic_square.bmp</htmlLinuxPicture>',
           '   <renderPicture>./images/Synthetic_square.bmp</renderPicture>',
           f'   <numMod>{len(SPEEDS)}</numMod>', f'   <numTri>{len(TRIS)}</numTri>',
           f'   <maxSpeed>{max(SPEEDS):.6f}</maxSpeed>', f'   <maxForce>{max(FORCES):.6f}</maxForce>']
    for name, values in (('speedList', SPEEDS), ('forceList', FORCES)):
        out.append(f'   <{name} type="array">')
        out += [f'      <value>{v:.6f}</value>' for v in values]
        out.append(f'   </{name}>')
    for t in TRIS:
        out.append('   <tri type="array">')
        out += [f'      <value>{v}</value>' for v in t]
        out.append('   </tri>')
    out += ['   <DTpicture>..\\..\\DelaunayTriangulationImages\\DT_Synthetic.png</DTpicture>',
            '   <LinuxDTpicture>../../DelaunayTriangulationImages/DT_Synthetic.png</LinuxDTpicture>',
            f'   <numARCoeff>{numar}</numARCoeff>', f'   <numMACoeff>{numma}</numMACoeff>']
    for m in range(len(SPEEDS)):
        a = poly_from_pairs(ar_pairs[m])
        out += ['   <model>', f'      <modNum>{m + 1}</modNum>', '      <ARcoeff>']
        out += [f'         <value>{v:.20f}</value>' for v in a]
        out += ['      </ARcoeff>', '      <ARlsf>']
        out += [f'         <value>{v:.6f}</value>' for v in lsf(a)]
        out.append('      </ARlsf>')
        if ma_pairs:
            b = poly_from_pairs(ma_pairs[m])
            out.append('      <MAcoeff>')
            out += [f'         <value>{v:.20f}</value>' for v in b]
            out += ['      </MAcoeff>', '      <MAlsf>']
            out += [f'         <value>{v:.6f}</value>' for v in lsf(b)]
            out.append('      </MAlsf>')
        out.append(f'      <var>{variances[m]:.6f}</var>')
        if ma_pairs:
            out.append(f'      <gain>{gains[m]:.6f}</gain>')
        out += [f'      <speedMod>{SPEEDS[m]:.6f}</speedMod>', f'      <forceMod>{FORCES[m]:.6f}</forceMod>',
                '   </model>']
    out.append('</modelSet>')
    with open(path, 'w') as f:
        f.write('\n'.join(out) + '\n')


def pairs(base):
    return [[(r, th * (1 + 0.05 * m)) for r, th in base] for m in range(4)]


# 1 kHz ARMA set, as CreateResampledModels.m writes them: AR(6), MA(4)
write('Models_Toolkit 1kHz ARMA.xml', 'Toolkit 1kHz ARMA', 1000,
      pairs([(0.9, 0.5), (0.8, 1.4), (0.7, 2.3)]), pairs([(0.6, 0.9), (0.5, 2.0)]),
      [0.004, 0.02, 0.01, 0.05], [1.5, 2.0, 1.2, 3.0])
# 10 kHz AR set, as the toolkit's original models: AR(8)
write('Models_Toolkit 10kHz AR.xml', 'Toolkit 10kHz AR', 10000,
      pairs([(0.95, 0.1), (0.9, 0.4), (0.8, 1.2), (0.7, 2.5)]), None,
      [0.002, 0.01, 0.005, 0.03], None)
