"""Re-derive S002's decision and Taguchi tables from its own printed numbers.

S002 ("Optimization Acceleration and Contact Force of Space Slider-Crank
Mechanism with Spherical Clearance Joints", Mathematical Modelling of Engineering Problems 11(10),
2024, doi 10.18280/mmep.111017) ranks 27 simulated runs of an L27 by two smaller-the-better
responses: the slider's maximum acceleration D [m/s²] and the contact force S in the revolute
clearance joint [N].

Method
------
1. **Transcription.** The project's text copy of the paper has no page numbers and lacks Table 4
   (the raw responses), Table 7 (S/N ratios) and Table 12 (SAW; its scores are the Q_i column of
   Table 13). Transcribed below, digit for digit, with the table they come from: Table 5 (MEREC,
   Section 4.2), Table 6 (GRA, Section 4.3), Table 8 (level means of the grade, Section 4.5),
   Table 9 (ANOVA, Section 4.7), Table 10 (model summary), Table 11 (TOPSIS, Section 4.8),
   Table 13 (WASPAS, Section 4.10), the prediction of Section 4.7 and the optimum of the abstract.
   Ranks that the copy renders as illegible glyphs are None. The transcription is checked a
   second time by each table's own identities (e.g. Δ = 1 − D*, ψ = Σ w γ, b = w n, Q = Σ v,
   A = 0.9 Q + 0.1 P, CC = S⁻/(S⁺ + S⁻)); a misread digit shows as one row off.
2. **The responses, reconstructed.** Table 5's h_ij is MEREC's normalisation of a cost criterion,
   a_ij / max_i a_ij, so each response is known up to its scale from h; the abstract's optimum
   (run 1: 32.72 m/s² and 1.3452 kN) fixes the scale: a_i = a_1 h_i / h_1. Tables 6 (D*),
   11 (a/‖a‖) and 13 (min a/a) give three more scale-free copies, compared with it.
3. **Recomputation** with the project's implementations (``twin/studies/mcdm.py``,
   ``twin/studies/taguchi.py``): MEREC as published by its authors; GRA, TOPSIS, SAW, WASPAS (the
   standard form and the paper's variant) with the paper's weights and with MEREC's; the L27
   (x = crank length in column 1, y = clearance in column 2, z = friction in column 5, t = speed in
   column 8; found by matching Table 8) with the paper's grade: level means, ANOVA with the
   interactions x*y, x*z, x*t, model summary, prediction and its confidence interval; and the
   Taguchi analysis (smaller-the-better S/N) of the two reconstructed responses themselves.

Run: ``.venv/bin/python analysis/s002_paper_tables.py`` (a second or two). Writes
``analysis/results/s002/paper_tables.json`` (every number), ``paper_tables.md`` (the comparison
tables) and ``responses_reconstructed.csv`` (the input of ``twin study mcdm`` and ``twin study
taguchi-analyze``). The reading of these numbers is ``analysis/results/s002/README.md``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
from scipy.stats import f as f_dist

from twin.studies import mcdm, taguchi
from twin.provenance import stamped, with_stamp_line

# ---------------------------------------------------------------------------- transcription
#: abstract and conclusion: run 1 (the optimum) has D = 32.72 m/s², S = 1.3452 kN
D1_MS2, S1_N = 32.72, 1345.2
#: Section 4.2 and Table 5: the MEREC weights of D and S
W_PAPER = (0.5814, 0.4186)
#: Table 5 (Section 4.2): h_ij (D, S), S_i, the two columns headed b_ij in the copy (S'_ij of Eq. 5; D, S), E_j (D, S)
T5 = [
    (0.2864, 0.1281, 0.9755, 0.4856, 0.7067, 0.4899, 0.2211),  # 1
    (0.4476, 0.1672, 0.8312, 0.3379, 0.6388, 0.4934, 0.3009),  # 2
    (0.6445, 0.1863, 0.7227, 0.1985, 0.6099, 0.5241, 0.4114),  # 3
    (0.3603, 0.1519, 0.8972, 0.4124, 0.6639, 0.4849, 0.2516),  # 4
    (0.5486, 0.1679, 0.7850, 0.2625, 0.6378, 0.5225, 0.3753),  # 5
    (0.6198, 0.1011, 0.8692, 0.2145, 0.7636, 0.6548, 0.5491),  # 6
    (0.4435, 0.1578, 0.8457, 0.3411, 0.6540, 0.5046, 0.3129),  # 7
    (0.4792, 0.0964, 0.9313, 0.3132, 0.7747, 0.6180, 0.4615),  # 8
    (0.7017, 0.1121, 0.8204, 0.1631, 0.7392, 0.6573, 0.5761),  # 9
    (0.4596, 0.1177, 0.8995, 0.3284, 0.7274, 0.5712, 0.3991),  # 10
    (0.5852, 0.1954, 0.7345, 0.2374, 0.5969, 0.4971, 0.3595),  # 11
    (0.7299, 0.2938, 0.5709, 0.1462, 0.4778, 0.4247, 0.3315),  # 12
    (0.5498, 0.2049, 0.7380, 0.2617, 0.5837, 0.4763, 0.3220),  # 13
    (0.6681, 0.2850, 0.6039, 0.1837, 0.4871, 0.4202, 0.3034),  # 14
    (0.6957, 0.2972, 0.5811, 0.1667, 0.4741, 0.4144, 0.3074),  # 15
    (0.6316, 0.2812, 0.6228, 0.2068, 0.4912, 0.4160, 0.2844),  # 16
    (0.6163, 0.2798, 0.6307, 0.2167, 0.4928, 0.4140, 0.2761),  # 17
    (0.7676, 0.3831, 0.4775, 0.1242, 0.3919, 0.3533, 0.2677),  # 18
    (0.8202, 0.4394, 0.4123, 0.0945, 0.3444, 0.3178, 0.2499),  # 19
    (0.8833, 0.5632, 0.2994, 0.0602, 0.2524, 0.2393, 0.1922),  # 20
    (0.9702, 0.7206, 0.1646, 0.0150, 0.1517, 0.1496, 0.1367),  # 21
    (0.9022, 0.6118, 0.2602, 0.0502, 0.2197, 0.2100, 0.1695),  # 22
    (0.9633, 0.7450, 0.1535, 0.0185, 0.1373, 0.1350, 0.1188),  # 23
    (0.9350, 0.8217, 0.1238, 0.0331, 0.0937, 0.0908, 0.0606),  # 24
    (0.9870, 0.7678, 0.1299, 0.0065, 0.1241, 0.1234, 0.1176),  # 25
    (0.9239, 0.8261, 0.1267, 0.0388, 0.0912, 0.0879, 0.0524),  # 26
    (1.0000, 1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000),  # 27
]
#: Table 6 (Section 4.3): D*(1), D*(2), Δ(1), Δ(2), γ(1), γ(2), ψ
T6 = [
    (1.0000, 0.9650, 0.0000, 0.0350, 1.0000, 0.9346, 0.9726),  # 1
    (0.7740, 0.9220, 0.2260, 0.0780, 0.6887, 0.8651, 0.7625),  # 2
    (0.4980, 0.9010, 0.5020, 0.0990, 0.4990, 0.8347, 0.6395),  # 3
    (0.8960, 0.9390, 0.1040, 0.0610, 0.8278, 0.8913, 0.8544),  # 4
    (0.6330, 0.9210, 0.3670, 0.0790, 0.5767, 0.8636, 0.6968),  # 5
    (0.5330, 0.9950, 0.4670, 0.0050, 0.5171, 0.9901, 0.7151),  # 6
    (0.7800, 0.9320, 0.2200, 0.0680, 0.6944, 0.8803, 0.7722),  # 7
    (0.7300, 1.0000, 0.2700, 0.0000, 0.6494, 1.0000, 0.7962),  # 8
    (0.4180, 0.9830, 0.5820, 0.0170, 0.4621, 0.9671, 0.6735),  # 9
    (0.7570, 0.9760, 0.2430, 0.0240, 0.6729, 0.9542, 0.7907),  # 10
    (0.5810, 0.8900, 0.4190, 0.1100, 0.5441, 0.8197, 0.6595),  # 11
    (0.3790, 0.7820, 0.6210, 0.2180, 0.4460, 0.6964, 0.5508),  # 12
    (0.6310, 0.8800, 0.3690, 0.1200, 0.5754, 0.8065, 0.6721),  # 13
    (0.4650, 0.7910, 0.5350, 0.2090, 0.4831, 0.7052, 0.5761),  # 14
    (0.4260, 0.7780, 0.5740, 0.2220, 0.4655, 0.6925, 0.5605),  # 15
    (0.5160, 0.7950, 0.4840, 0.2050, 0.5081, 0.7092, 0.5923),  # 16
    (0.5380, 0.7970, 0.4620, 0.2030, 0.5198, 0.7112, 0.5999),  # 17
    (0.3260, 0.6830, 0.6740, 0.3170, 0.4259, 0.6120, 0.5038),  # 18
    (0.2520, 0.6200, 0.7480, 0.3800, 0.4006, 0.5682, 0.4708),  # 19
    (0.1640, 0.4830, 0.8360, 0.5170, 0.3743, 0.4916, 0.4234),  # 20
    (0.0420, 0.3090, 0.9580, 0.6910, 0.3429, 0.4198, 0.3751),  # 21
    (0.1370, 0.4300, 0.8630, 0.5700, 0.3668, 0.4673, 0.4089),  # 22
    (0.0510, 0.2820, 0.9490, 0.7180, 0.3451, 0.4105, 0.3725),  # 23
    (0.0910, 0.1970, 0.9090, 0.8030, 0.3549, 0.3837, 0.3670),  # 24
    (0.0180, 0.2570, 0.9820, 0.7430, 0.3374, 0.4023, 0.3646),  # 25
    (0.1070, 0.1920, 0.8930, 0.8080, 0.3589, 0.3823, 0.3687),  # 26
    (0.0000, 0.0000, 1.0000, 1.0000, 0.3333, 0.3333, 0.3333),  # 27
]
#: Table 11 (Section 4.8; its caption is missing in the copy): n_ij (D, S), b_ij (D, S), S+, S-, CC
T11 = [
    (0.0767, 0.0535, 0.0446, 0.0224, 0.0056, 0.1884, 0.9714),  # 1
    (0.1198, 0.0698, 0.0697, 0.0292, 0.0280, 0.1689, 0.8580),  # 2
    (0.1725, 0.0777, 0.1003, 0.0325, 0.0579, 0.1525, 0.7248),  # 3
    (0.0964, 0.0633, 0.0561, 0.0265, 0.0150, 0.1784, 0.9223),  # 4
    (0.1469, 0.0700, 0.0854, 0.0293, 0.0427, 0.1614, 0.7909),  # 5
    (0.1659, 0.0422, 0.0965, 0.0177, 0.0519, 0.1677, 0.7638),  # 6
    (0.1187, 0.0658, 0.0690, 0.0276, 0.0267, 0.1707, 0.8647),  # 7
    (0.1283, 0.0402, 0.0746, 0.0168, 0.0300, 0.1774, 0.8553),  # 8
    (0.1878, 0.0468, 0.1092, 0.0196, 0.0647, 0.1618, 0.7144),  # 9
    (0.1230, 0.0491, 0.0715, 0.0206, 0.0272, 0.1755, 0.8658),  # 10
    (0.1566, 0.0815, 0.0911, 0.0341, 0.0496, 0.1546, 0.7571),  # 11
    (0.1954, 0.1225, 0.1136, 0.0513, 0.0771, 0.1303, 0.6281),  # 12
    (0.1472, 0.0855, 0.0856, 0.0358, 0.0452, 0.1555, 0.7750),  # 13
    (0.1788, 0.1189, 0.1040, 0.0498, 0.0679, 0.1351, 0.6655),  # 14
    (0.1862, 0.1240, 0.1083, 0.0519, 0.0727, 0.1315, 0.6440),  # 15
    (0.1691, 0.1173, 0.0983, 0.0491, 0.0627, 0.1380, 0.6877),  # 16
    (0.1650, 0.1167, 0.0959, 0.0489, 0.0605, 0.1392, 0.6970),  # 17
    (0.2055, 0.1598, 0.1195, 0.0669, 0.0901, 0.1136, 0.5578),  # 18
    (0.2195, 0.1833, 0.1276, 0.0767, 0.1024, 0.1018, 0.4985),  # 19
    (0.2364, 0.2349, 0.1375, 0.0983, 0.1236, 0.0784, 0.3882),  # 20
    (0.2597, 0.3006, 0.1510, 0.1258, 0.1523, 0.0490, 0.2434),  # 21
    (0.2415, 0.2552, 0.1404, 0.1068, 0.1315, 0.0695, 0.3457),  # 22
    (0.2579, 0.3108, 0.1499, 0.1301, 0.1547, 0.0449, 0.2249),  # 23
    (0.2503, 0.3427, 0.1455, 0.1435, 0.1619, 0.0327, 0.1682),  # 24
    (0.2642, 0.3203, 0.1536, 0.1341, 0.1601, 0.0406, 0.2023),  # 25
    (0.2473, 0.3446, 0.1438, 0.1442, 0.1615, 0.0326, 0.1679),  # 26
    (0.2677, 0.4171, 0.1556, 0.1746, 0.1929, 0.0000, 0.0000),  # 27
]
#: Table 13 (Section 4.10): n_ij (D, S), v_ij (D, S), Q, P, A
T13 = [
    (1.0000, 0.7519, 0.5814, 0.3147, 0.8961, 0.4497, 0.8515),  # 1
    (0.6400, 0.5761, 0.3721, 0.2412, 0.6132, 0.3103, 0.5830),  # 2
    (0.4444, 0.5173, 0.2584, 0.2165, 0.4749, 0.2400, 0.4514),  # 3
    (0.7950, 0.6345, 0.4622, 0.2656, 0.7278, 0.3665, 0.6917),  # 4
    (0.5221, 0.5739, 0.3036, 0.2402, 0.5438, 0.2752, 0.5169),  # 5
    (0.4622, 0.9532, 0.2687, 0.3990, 0.6677, 0.3171, 0.6326),  # 6
    (0.6458, 0.6106, 0.3755, 0.2556, 0.6310, 0.3196, 0.5999),  # 7
    (0.5977, 1.0000, 0.3475, 0.4186, 0.7661, 0.3757, 0.7271),  # 8
    (0.4082, 0.8595, 0.2373, 0.3598, 0.5971, 0.2825, 0.5657),  # 9
    (0.6233, 0.8185, 0.3624, 0.3426, 0.7050, 0.3540, 0.6699),  # 10
    (0.4895, 0.4931, 0.2846, 0.2064, 0.4910, 0.2488, 0.4668),  # 11
    (0.3925, 0.3280, 0.2282, 0.1373, 0.3655, 0.1845, 0.3474),  # 12
    (0.5210, 0.4702, 0.3029, 0.1968, 0.4997, 0.2529, 0.4750),  # 13
    (0.4287, 0.3380, 0.2493, 0.1415, 0.3908, 0.1967, 0.3714),  # 14
    (0.4117, 0.3241, 0.2394, 0.1357, 0.3751, 0.1887, 0.3564),  # 15
    (0.4535, 0.3426, 0.2637, 0.1434, 0.4071, 0.2044, 0.3868),  # 16
    (0.4648, 0.3444, 0.2702, 0.1442, 0.4144, 0.2077, 0.3937),  # 17
    (0.3732, 0.2515, 0.2170, 0.1053, 0.3222, 0.1603, 0.3060),  # 18
    (0.3492, 0.2193, 0.2030, 0.0918, 0.2948, 0.1456, 0.2799),  # 19
    (0.3243, 0.1711, 0.1885, 0.0716, 0.2602, 0.1257, 0.2467),  # 20
    (0.2952, 0.1337, 0.1716, 0.0560, 0.2276, 0.1074, 0.2156),  # 21
    (0.3175, 0.1575, 0.1846, 0.0659, 0.2505, 0.1200, 0.2375),  # 22
    (0.2973, 0.1293, 0.1729, 0.0541, 0.2270, 0.1063, 0.2149),  # 23
    (0.3064, 0.1173, 0.1781, 0.0491, 0.2272, 0.1038, 0.2149),  # 24
    (0.2902, 0.1255, 0.1687, 0.0525, 0.2213, 0.1035, 0.2095),  # 25
    (0.3100, 0.1166, 0.1803, 0.0488, 0.2291, 0.1043, 0.2166),  # 26
    (0.2864, 0.0964, 0.1665, 0.0403, 0.2069, 0.0920, 0.1954),  # 27
]
#: printed ranks (None: illegible in the copy). Table 6: run 1's rank cell is empty, the text calls it rank 1
RANK_T6 = [1, 6, 12, 2, 8, 7, 5, 3, 9, 4, 11, 17, 10, 15, 16, 14, 13, 18, 19, 20, 22, 21, 23, 25, 26, 24, 27]
RANK_T11 = [1, 5, 11, 2, 7, 9, None, 6, 12, None, 10, 17, 8, 15, 16, 14, 13, 18, 19, 20, 22, 21, 23, 25, 24, 26, 27]
RANK_T13 = [1, 7, 12, 3, 9, 5, 6, None, 8, 4, 11, 17, 10, 15, 16, 14, 13, 18, 19, 20, 23, 21, 24, 25, 26, 22, 27]
#: Table 8 (Section 4.5): level means of the grade, levels 1-3 of x, y, z, t, then delta
T8 = {"x": (0.7861, 0.6310, 0.3931, 0.3929), "y": (0.6422, 0.5961, 0.5719, 0.0704),
      "z": (0.6669, 0.5998, 0.5435, 0.1234), "t": (0.6424, 0.6033, 0.5645, 0.0779)}
#: Table 9 (Section 4.7): DF, Seq SS, contribution %, Adj MS, F, P
T9 = {"x": (2, 0.704990, 83.32, 0.352495, 1074.79, 0.000), "y": (2, 0.023005, 2.72, 0.011503, 35.07, 0.000),
      "z": (2, 0.068661, 8.11, 0.034330, 104.68, 0.000), "t": (2, 0.027308, 3.23, 0.013654, 41.63, 0.000),
      "x*y": (4, 0.004968, 0.59, 0.001742, 5.79, 0.042), "x*z": (4, 0.008842, 1.04, 0.002210, 6.74, 0.021),
      "x*t": (4, 0.006370, 0.75, 0.001593, 4.86, 0.043), "Error": (6, 0.001968, 0.23, 0.000328, None, None),
      "Total": (26, 0.846112, 100.00, None, None, None)}
#: Table 10: S, R-sq %, R-sq(adj) %, PRESS, R-sq(pred) %
T10 = (0.0181098, 99.77, 98.99, 0.0398478, 97.29)
#: Section 4.7: prediction 0.7861 + 0.6422 + 0.6669 + 0.6424 - 3*0.6034 = 0.9273, "optimal" 0.967,
#: error 3.97 %; CI inputs F0.05(1,6) = 5.9874, Ve = 0.000328, R = 20, Re = 1, n = 27
PRED = {"grand_mean": 0.6034, "predicted": 0.9273, "optimal": 0.967, "error_pct": 3.97, "F": 5.9874, "Ve": 0.000328}
FACTORS = ("x", "y", "z", "t")  # crank length, clearance, friction, speed


def _a(rows, cols):
    return np.array([[r[c] for c in cols] for r in rows])


def check_identities() -> dict:
    """The second check of the transcription: each table against its own identities (max |diff|)."""
    t5, t6, t11, t13 = (np.array(t) for t in (T5, T6, T11, T13))
    w = np.array(W_PAPER)
    a = np.abs(np.log(t5[:, :2]))
    out = {
        "T5 S_i = ln(1 + mean|ln h|)": np.log1p(a.mean(1)) - t5[:, 2],
        "T5 S'(col D) = ln(1 + |ln h_D|/2)": np.log1p(a[:, 0] / 2) - t5[:, 3],
        "T5 S'(col S) = ln(1 + |ln h_S|/2)": np.log1p(a[:, 1] / 2) - t5[:, 4],
        "T5 E(col D) = S_i - S'(col D)": t5[:, 2] - t5[:, 3] - t5[:, 5],
        "T5 E(col S) = S'(col S) - S'(col D)": t5[:, 4] - t5[:, 3] - t5[:, 6],
        "T6 delta = 1 - D*": 1 - t6[:, :2] - t6[:, 2:4],
        "T6 gamma = 0.5/(delta + 0.5)": 0.5 / (t6[:, 2:4] + 0.5) - t6[:, 4:6],
        "T6 psi = w . gamma": t6[:, 4:6] @ w - t6[:, 6],
        "T11 b = w n": t11[:, :2] * w - t11[:, 2:4],
        "T11 S+ from b": np.sqrt(((t11[:, 2:4] - t11[:, 2:4].min(0)) ** 2).sum(1)) - t11[:, 4],
        "T11 S- from b": np.sqrt(((t11[:, 2:4] - t11[:, 2:4].max(0)) ** 2).sum(1)) - t11[:, 5],
        "T11 CC = S-/(S+ + S-)": t11[:, 5] / (t11[:, 4] + t11[:, 5]) - t11[:, 6],
        "T13 v = w n": t13[:, :2] * w - t13[:, 2:4],
        "T13 Q = sum v": t13[:, 2:4].sum(1) - t13[:, 4],
        "T13 P = prod v^w": np.prod(t13[:, 2:4] ** w, axis=1) - t13[:, 5],
        "T13 A = 0.9 Q + 0.1 P": 0.9 * t13[:, 4] + 0.1 * t13[:, 5] - t13[:, 6],
    }
    res = {}
    for k, d in out.items():
        d = np.atleast_2d(np.abs(d).T).T if d.ndim == 1 else np.abs(d)
        worst = np.unravel_index(np.argmax(d), d.shape)
        res[k] = {"max_abs_diff": float(d.max()), "worst_run": int(worst[0]) + 1}
    return res


def reconstruct() -> dict:
    """The responses from Table 5's h (scaled by run 1 = the abstract's optimum) and the three
    other scale-free copies, each scaled to the same run-1 value: the largest relative differences."""
    t5, t6, t11, t13 = (np.array(t) for t in (T5, T6, T11, T13))
    h = t5[:, :2]
    resp = h / h[0] * np.array([D1_MS2, S1_N])
    copies = {
        "Table 11 n = a/|a|": t11[:, :2] / t11[0, :2],
        "Table 13 n = min(a)/a": t13[0, :2] / t13[:, :2],
        # D* = (max - a)/(max - min) -> a/max = 1 - D*(1 - min/max), min/max from Table 5
        "Table 6 D*": (1 - t6[:, :2] * (1 - h.min(0))) / (1 - t6[0, :2] * (1 - h.min(0))),
    }
    ratio = h / h[0]
    dev = {k: {"max_rel_diff": [float(np.max(np.abs(c[:, j] / ratio[:, j] - 1))) for j in range(2)],
               "worst_run": [int(np.argmax(np.abs(c[:, j] / ratio[:, j] - 1))) + 1 for j in range(2)]}
           for k, c in copies.items()}
    return {"D_ms2": resp[:, 0], "S_N": resp[:, 1], "copies": dev}


def _cmp(ours, printed) -> dict:
    ours, printed = np.asarray(ours, float), np.asarray(printed, float)
    d = np.abs(ours - printed)
    return {"max_abs_diff": float(d.max()), "worst_run": int(np.argmax(d)) + 1}


def _rank_cmp(ours, printed) -> dict:
    diff = [i + 1 for i, (o, p) in enumerate(zip(ours, printed)) if p is not None and o != p]
    return {"runs_differing": diff, "illegible": [i + 1 for i, p in enumerate(printed) if p is None],
            "ours": [int(v) for v in ours]}


def decisions(x: np.ndarray) -> dict:
    """MEREC, GRA, TOPSIS, SAW, WASPAS recomputed from the reconstructed responses."""
    cost = [False, False]
    t5, t6, t11, t13 = (np.array(t) for t in (T5, T6, T11, T13))
    md = mcdm.merec_details(x, cost)
    md_h = mcdm.merec_details(t5[:, :2], cost)  # from the printed h directly (h is already x/max)
    # the paper's arithmetic: its E columns summed, as printed
    e_cols = t5[:, 5:7].sum(0)
    out: dict = {
        "merec": {
            "weights_published_method": md["weights"].tolist(),
            "weights_published_method_from_printed_h": md_h["weights"].tolist(),
            "E_published_method": md["E"].tolist(),
            "paper_weights": list(W_PAPER),
            "paper_E_column_sums": e_cols.tolist(),
            "paper_E_column_sums_normalized": (e_cols / e_cols.sum()).tolist(),
            "S_i_vs_printed": _cmp(md_h["S"], t5[:, 2]),
            # column of the copy's 'D' = S' with S removed (D kept); 'S' = S' with D removed
            "S_removed_D_vs_printed_col_S": _cmp(md_h["S_removed"][:, 0], t5[:, 4]),
            "S_removed_S_vs_printed_col_D": _cmp(md_h["S_removed"][:, 1], t5[:, 3]),
        }
    }
    for label, w in (("paper_weights", np.array(W_PAPER)), ("merec_weights", md["weights"]),
                     ("equal_weights", np.array([0.5, 0.5]))):
        g = mcdm.gra(x, cost, w)
        tp = mcdm.topsis(x, cost, w)
        sw = mcdm.saw(x, cost, w)
        ws = mcdm.waspas(x, cost, w, 0.9)
        wp = mcdm.waspas_paper(x, cost, w, 0.9)
        r = {"gra": g["scores"], "topsis": tp["scores"], "saw": sw["scores"], "waspas_standard": ws["scores"],
             "waspas_paper": wp["scores"]}
        out[label] = {"weights": w.tolist(),
                      "scores": {k: v.tolist() for k, v in r.items()},
                      "ranks": {k: mcdm.ranks(v).tolist() for k, v in r.items()},
                      "best_run": {k: int(np.argmax(v)) + 1 for k, v in r.items()}}
        if label == "paper_weights":
            out[label]["vs_printed"] = {
                "T6 D*": _cmp(g["normalized"], t6[:, :2]), "T6 gamma": _cmp(g["coefficient"], t6[:, 4:6]),
                "T6 psi": _cmp(g["scores"], t6[:, 6]), "T6 rank": _rank_cmp(mcdm.ranks(g["scores"]), RANK_T6),
                "T11 n": _cmp(tp["normalized"], t11[:, :2]), "T11 b": _cmp(tp["weighted"], t11[:, 2:4]),
                "T11 S+": _cmp(tp["d_plus"], t11[:, 4]), "T11 S-": _cmp(tp["d_minus"], t11[:, 5]),
                "T11 CC": _cmp(tp["scores"], t11[:, 6]),
                "T11 rank": _rank_cmp(mcdm.ranks(tp["scores"]), RANK_T11),
                "T13 n": _cmp(wp["normalized"], t13[:, :2]), "T13 Q (= SAW)": _cmp(wp["Q"], t13[:, 4]),
                "T13 P": _cmp(wp["P"], t13[:, 5]), "T13 A": _cmp(wp["scores"], t13[:, 6]),
                "T13 rank": _rank_cmp(mcdm.ranks(wp["scores"]), RANK_T13),
                "T13 rank vs printed A ranked": _rank_cmp(mcdm.ranks(t13[:, 6]), RANK_T13),
                "T13 rank, standard WASPAS": _rank_cmp(mcdm.ranks(ws["scores"]), RANK_T13),
                "waspas_paper_c": wp["c"],
            }
    return out


def taguchi_grade() -> dict:
    """The paper's Taguchi analysis of the grey relational grade (Tables 8-10, Section 4.7)."""
    t6 = np.array(T6)
    lv = np.column_stack([taguchi.L27[:, c - 1] - 1 for c in (1, 2, 5, 8)])
    inter = [(0, 1), (0, 2), (0, 3)]
    grades = {"equal-weight grade (gamma1 + gamma2)/2 of Table 6": t6[:, 4:6].mean(1),
              "Table 6 psi (weights 0.5814/0.4186)": t6[:, 6]}
    out: dict = {"assignment": {"x": 1, "y": 2, "z": 5, "t": 8},
                 "assignment_search": {}}
    # which L27 column reproduces Table 8's level means of each factor (equal-weight grade)
    g = grades["equal-weight grade (gamma1 + gamma2)/2 of Table 6"]
    for f in FACTORS:
        errs = [float(np.max(np.abs(np.array([g[taguchi.L27[:, c] == lvl].mean() for lvl in (1, 2, 3)])
                                    - np.array(T8[f][:3])))) for c in range(13)]
        out["assignment_search"][f] = {"best_column": int(np.argmin(errs)) + 1, "max_abs_diff": min(errs),
                                       "next_best": sorted(errs)[1]}
    for name, y in grades.items():
        a = taguchi.analyze(lv, y, FACTORS, "max", inter)
        sn = taguchi.sn_ratio(y, "larger")
        s = taguchi.analyze(lv, sn, FACTORS, "max", inter)
        rows = {r["source"]: r for r in a["anova"]["rows"]}
        p = a["prediction"]
        fc = float(f_dist.ppf(0.95, 1, a["anova"]["error_dof"]))
        out[name] = {
            "grand_mean": float(y.mean()), "main_effects": a["main_effects"], "delta": a["delta"], "rank": a["rank"],
            "T8_max_abs_diff": float(max(np.max(np.abs(np.array(a["main_effects"][i]) - np.array(T8[f][:3])))
                                         for i, f in enumerate(FACTORS))),
            "anova": {k: {kk: r[kk] for kk in ("dof", "ss", "ms", "f", "p", "contribution_pct")} for k, r in rows.items()},
            "summary": a["anova"]["summary"],
            "prediction_all_four": p["predicted"], "n_eff": p["n_eff"], "F_0.05(1,fe)": fc,
            "ci_pop": p["ci_pop"], "ci_ce_R1": p["ci_ce"],
            "run1": float(y[0]),
            "sn_larger": {"values": sn.tolist(), "main_effects": s["main_effects"], "delta": s["delta"],
                          "rank": s["rank"], "optimum_levels": s["optimum_levels"]},
        }
    # the paper's own arithmetic on its printed numbers
    t9 = T9
    ms_err = t9["Error"][1] / t9["Error"][0]
    out["paper_arithmetic"] = {
        "Table 9 SS sum": sum(v[1] for k, v in t9.items() if k != "Total"),
        "Table 9 MS = SS/DF": {k: v[1] / v[0] for k, v in t9.items() if k != "Total"},
        "Table 9 F = MS/MS_error (printed MS)": {k: v[3] / ms_err for k, v in t9.items() if v[3] is not None and k not in ("Error",)},
        "Table 9 F = (SS/DF)/MS_error": {k: v[1] / v[0] / ms_err for k, v in t9.items() if k not in ("Error", "Total")},
        "Table 9 p from printed F": {k: float(f_dist.sf(v[4], v[0], 6)) for k, v in t9.items() if v[4] is not None},
        "Table 9 p from SS/DF": {k: float(f_dist.sf(v[1] / v[0] / ms_err, v[0], 6)) for k, v in t9.items()
                                 if k not in ("Error", "Total")},
        "Table 9 contribution": {k: 100 * v[1] / t9["Total"][1] for k, v in t9.items()},
        "Table 10 from Table 9": {"S": ms_err ** 0.5, "R-sq": 100 * (1 - t9["Error"][1] / t9["Total"][1]),
                                  "R-sq(adj)": 100 * (1 - ms_err / (t9["Total"][1] / 26)),
                                  "R-sq(pred) from PRESS": 100 * (1 - T10[3] / t9["Total"][1])},
        "prediction 0.7861+0.6422+0.6669+0.6424-3*0.6034": 0.7861 + 0.6422 + 0.6669 + 0.6424 - 3 * 0.6034,
        "F_0.05(1,6)": float(f_dist.ppf(0.95, 1, 6)),
        "CI_ce with n_eff = 27/9, Re = 1": (PRED["F"] * PRED["Ve"] * (1 / 3 + 1)) ** 0.5,
        "CI_pop with n_eff = 27/9": (PRED["F"] * PRED["Ve"] / 3) ** 0.5,
        "error (0.967 - 0.9273)/0.967 %": 100 * (0.967 - 0.9273) / 0.967,
        "error (0.967 - 0.9273)/0.9273 %": 100 * (0.967 - 0.9273) / 0.9273,
        "Table 8 delta = level1 - level3": {f: T8[f][0] - T8[f][2] for f in FACTORS},
    }
    return out


def taguchi_responses(x: np.ndarray) -> dict:
    """The project's Taguchi analysis of the two reconstructed responses (smaller-the-better)."""
    lv = np.column_stack([taguchi.L27[:, c - 1] - 1 for c in (1, 2, 5, 8)])
    out = {}
    for j, name in enumerate(("D_ms2", "S_N")):
        y = x[:, j]
        for label, inter in (("main effects", []), ("with x*y, x*z, x*t", [(0, 1), (0, 2), (0, 3)])):
            raw = taguchi.analyze(lv, y, FACTORS, "min", inter)
            sn = taguchi.analyze(lv, taguchi.sn_ratio(y, "smaller"), FACTORS, "max", inter)
            out[f"{name}, {label}"] = {
                "raw_main_effects": raw["main_effects"], "raw_optimum_levels": raw["optimum_levels"],
                "raw_anova": {r["source"]: {k: r[k] for k in ("dof", "ss", "f", "p", "contribution_pct")}
                              for r in raw["anova"]["rows"]},
                "raw_prediction": raw["prediction"],
                "sn_main_effects": sn["main_effects"], "sn_rank": sn["rank"], "sn_optimum_levels": sn["optimum_levels"],
                "sn_anova": {r["source"]: {k: r[k] for k in ("dof", "ss", "f", "p", "contribution_pct")}
                             for r in sn["anova"]["rows"]},
                "sn_prediction": sn["prediction"],
                "run1": float(y[0]), "run1_sn": float(taguchi.sn_ratio(y[:1], "smaller")[0]),
            }
    return out


def _md(res: dict) -> str:
    """paper_tables.md: the comparison tables."""
    L = ["# S002's tables re-derived (generated by analysis/s002_paper_tables.py)", "",
         "## Transcription checked against each table's own identities (max |diff|, worst run)", "",
         "| identity | max abs diff | run |", "|---|---|---|"]
    L += [f"| {k} | {v['max_abs_diff']:.2e} | {v['worst_run']} |" for k, v in res["identities"].items()]
    L += ["", "## Responses reconstructed from Table 5's h (run 1 = 32.72 m/s², 1345.2 N)", "",
          "| run | x | y | z | t | D [m/s²] | S [N] |", "|---|---|---|---|---|---|---|"]
    d = taguchi.s002_design()
    for i in range(27):
        L.append(f"| {i + 1} | {d['crank_length'][i]:g} | {d['clearance'][i]:g} | {d['friction'][i]:g} | "
                 f"{d['speed'][i]:g} | {res['responses']['D_ms2'][i]:.2f} | {res['responses']['S_N'][i]:.1f} |")
    L += ["", "Other copies of the same responses (scaled to run 1), largest relative difference from Table 5's:", ""]
    L += [f"* {k}: D {v['max_rel_diff'][0]:.2e} (run {v['worst_run'][0]}), S {v['max_rel_diff'][1]:.2e} "
          f"(run {v['worst_run'][1]})" for k, v in res["responses"]["copies"].items()]
    m = res["decisions"]["merec"]
    L += ["", "## MEREC", "",
          f"* published method, reconstructed responses: w_D = {m['weights_published_method'][0]:.4f}, "
          f"w_S = {m['weights_published_method'][1]:.4f} (from the printed h: "
          f"{m['weights_published_method_from_printed_h'][0]:.4f}, {m['weights_published_method_from_printed_h'][1]:.4f})",
          f"* paper: {m['paper_weights']}; its E columns summed: {[round(v, 4) for v in m['paper_E_column_sums']]} -> "
          f"{[round(v, 4) for v in m['paper_E_column_sums_normalized']]}", ""]
    L += ["## Recomputed with the paper's weights against the printed tables", "", "| quantity | max abs diff | run |",
          "|---|---|---|"]
    for k, v in res["decisions"]["paper_weights"]["vs_printed"].items():
        if isinstance(v, dict) and "max_abs_diff" in v:
            L.append(f"| {k} | {v['max_abs_diff']:.2e} | {v['worst_run']} |")
    L += ["", "| ranks | runs whose printed rank differs | illegible |", "|---|---|---|"]
    for k, v in res["decisions"]["paper_weights"]["vs_printed"].items():
        if isinstance(v, dict) and "runs_differing" in v:
            L.append(f"| {k} | {v['runs_differing'] or 'none'} | {v['illegible'] or ''} |")
    L += ["", "## Ranks by method and weights (run order)", "", "| weights | method | best run | ranks |", "|---|---|---|---|"]
    for lab in ("paper_weights", "merec_weights", "equal_weights"):
        blk = res["decisions"][lab]
        for k, r in blk["ranks"].items():
            L.append(f"| {lab} {[round(w, 4) for w in blk['weights']]} | {k} | {blk['best_run'][k]} | {r} |")
    tg = res["taguchi_grade"]
    L += ["", "## Taguchi analysis of the grade (L27 columns x=1, y=2, z=5, t=8)", "",
          "| factor | best column | max |diff| to Table 8 | next best column's |", "|---|---|---|---|"]
    L += [f"| {f} | {v['best_column']} | {v['max_abs_diff']:.4f} | {v['next_best']:.4f} |"
          for f, v in tg["assignment_search"].items()]
    for name in [k for k in tg if "grade" in k or "psi" in k]:
        g = tg[name]
        L += ["", f"### {name}", "", f"grand mean {g['grand_mean']:.4f}; run 1 {g['run1']:.4f}; "
              f"prediction (x1 y1 z1 t1) {g['prediction_all_four']:.4f}; n_eff {g['n_eff']:.3g}; "
              f"CI_pop ±{g['ci_pop']:.4f}, CI_ce (R = 1) ±{g['ci_ce_R1']:.4f}; max |diff| to Table 8 "
              f"{g['T8_max_abs_diff']:.4f}", "",
              "| factor | level 1 | level 2 | level 3 | delta | rank | S/N rank |", "|---|---|---|---|---|---|---|"]
        for i, f in enumerate(FACTORS):
            me = g["main_effects"][i]
            L.append(f"| {f} | {me[0]:.4f} | {me[1]:.4f} | {me[2]:.4f} | {g['delta'][i]:.4f} | {g['rank'][i]} | "
                     f"{g['sn_larger']['rank'][i]} |")
        L += ["", "| source | DF | SS | MS | F | p | contribution % |", "|---|---|---|---|---|---|---|"]
        for k, r in g["anova"].items():
            L.append(f"| {k} | {r['dof']} | {r['ss']:.6f} | {'' if r['ms'] is None else format(r['ms'], '.6f')} | "
                     f"{'' if r['f'] is None else format(r['f'], '.2f')} | {'' if r['p'] is None else format(r['p'], '.3f')} | "
                     f"{r['contribution_pct']:.2f} |")
        s = g["summary"]
        L += ["", f"S {s['s']:.7f}, R-sq {100 * s['r_sq']:.2f} %, R-sq(adj) {100 * s['r_sq_adj']:.2f} %, "
              f"PRESS {s['press']:.7f}, R-sq(pred) {100 * s['r_sq_pred']:.2f} %"]
    L += ["", "## The paper's arithmetic on its own printed numbers", "", "```",
          json.dumps(tg["paper_arithmetic"], indent=1), "```", ""]
    L += ["## The reconstructed responses themselves (smaller-the-better)", ""]
    for k, v in res["taguchi_responses"].items():
        an = v["sn_anova"]
        L.append(f"* {k}: S/N best levels {[l + 1 for l in v['sn_optimum_levels']]}, S/N rank {v['sn_rank']}; "
                 "S/N contributions " + ", ".join(f"{s} {r['contribution_pct']:.1f} %" for s, r in an.items()
                                                 if s != "Total")
                 + f"; predicted S/N {v['sn_prediction']['predicted']:.2f} dB (run 1: {v['run1_sn']:.2f} dB)"
                 + (f" ± {v['sn_prediction']['ci_ce']:.2f}" if v['sn_prediction']['ci_ce'] else "")
                 + f"; predicted mean {v['raw_prediction']['predicted']:.4g} (run 1: {v['run1']:.4g})")
    return "\n".join(L) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "s002"))
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rec = reconstruct()
    x = np.column_stack([rec["D_ms2"], rec["S_N"]])
    res = {"identities": check_identities(),
           "responses": {"D_ms2": rec["D_ms2"].tolist(), "S_N": rec["S_N"].tolist(), "copies": rec["copies"]},
           "decisions": decisions(x), "taguchi_grade": taguchi_grade(), "taguchi_responses": taguchi_responses(x)}
    (out / "paper_tables.json").write_text(json.dumps(stamped(res), indent=1, default=float) + "\n")
    (out / "paper_tables.md").write_text(with_stamp_line(_md(res)))
    d = taguchi.s002_design()
    lines = ["run,crank_length_mm,clearance_mm,friction,speed_rpm,max_slider_accel_ms2,max_force_revolute_N"]
    for i in range(27):
        lines.append(f"{i + 1},{d['crank_length'][i]:g},{d['clearance'][i]:g},{d['friction'][i]:g},{d['speed'][i]:g},"
                     f"{x[i, 0]:.4f},{x[i, 1]:.2f}")
    (out / "responses_reconstructed.csv").write_text("\n".join(lines) + "\n")
    print(f"wrote {out / 'paper_tables.json'}, {out / 'paper_tables.md'}, {out / 'responses_reconstructed.csv'}")


if __name__ == "__main__":
    main()
