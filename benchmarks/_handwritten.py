"""The figures of the benchmarks not yet recorded by ``benchmarks/record.py``, as last written by hand (issue 36).

``docs/make_benchmarks.py`` uses an entry here only while ``benchmarks/results/NAME.json`` is missing or
``benchmarks/_summaries.py`` has no summary for it: ``PAGE[name]`` is the section's text (reStructuredText),
``README_ROWS[name]`` the README's headline row as it was. Once the benchmark is recorded and summarised, the
generated text replaces it: delete the entry then (``tests/test_benchmark_page.py`` says which are stale).
"""

from __future__ import annotations

PAGE: dict[str, str] = {
    "default_path": (
        '2026-12-04, load 7-8 (other jobs on the 2 cores), cache warm: **finger3 seeds 1-60: 60/60 exit 0**, '
        'springs within 0.22 % (median 0.08), masses within 1.60 % (median 0.34), 12 draws hung fingers down '
        'by the experiment (seeds 2, 3, 8, 11, 30, 32, 34, 36, 44, 48, 53, 60), none scaled; the tendon '
        "compliance not identified on every draw (our simulator's cable is rigid: never written); **finger2 "
        'seeds 1-60: 60/60 exit 0**, springs within 0.13 % (median 0.04), masses within 0.16 % (median 0.06),'
        ' seed 42 hung; no written file with a non-physical value (both models); hand seed 5: palm up, the '
        "five chains converged and adequate (91 s of fits); hand seed 6: hung, the thumb's fit flagged "
        '(residual coloured): exit 3'),
    "force_realism": (
        '2026-12-04, fresh seeds 201-206 (tuned on finger3 seed 1), load 6-9, cache warm: finger3 sensor '
        '(identified + compensation) **6/6**, RMSE 1.56 % median (1.98 worst), overshoot 7.6 (8.4) %, rise 92'
        ' (97) ms; the rigid design and the shipped file 0/6 (the cable rings at 250 Hz: 32-34 % of the '
        'step); sensorless 6/6 within 10 % (5.69 % median, 6.08 worst; the shipped file 15.8 / 22.8 %); '
        'finger2 sensor 6/6 in every variant (RMSE 0.38 %, overshoot 1.5 %, rise 67 ms with compensation), '
        'sensorless identified 6/6 (4.8-5.5 %), shipped 1/6; the hand, seed 201: sensor within 0.22 % on the '
        'five forces, sensorless 5.1-10.0 % (**the 5 % goal missed**: a 5 % torque-constant error scales '
        "every identified torque and the encoder cannot see it); seed 202: the ring finger's fit lost its "
        'basin, its sensorless force 43 % off, the sensor loops within 0.11 %; seed 204: sensor within 0.22 '
        '%, sensorless 6.55 % (miss); seed 203: the index finger holds no force in any variant, the shipped '
        "file's included (the grasp scene of that drawn hand loses its contact), and the little finger's fit "
        'lost its basin (measured on main before the ``realism`` merge)'),
    "realism": (
        '2026-12-04, on main after every merge (the physical bounds of '
        ':mod:`~alpes_dyn.estimation.identification.bounds`, '
        "the observer's prediction threshold 25 times the floor), load 2-3, cache warm, the same outcome as "
        'on the ``realism`` branch before (threshold 15, load 3-8); seeds 401-420 (tuned on 301-320; two '
        'rules also drawn from 401-409: the delay tried after an observer refusal, each new fit judged '
        'again): **all**: 14 adequate, 2 silent misses (seed 417: m 6.2 %, 420: m 5.3 %), 6 refused (403, '
        "406, 411, 413, 416, 418: lost basin, the verdict naming a joint stop: the plant's j1 goes to -15 to "
        '-27 degrees palm up); the 14 adequate: K within 0.86 % (median 0.67), m within 6.24 % (1.73), EKF '
        'within 0.47 degree on every joint (0.40), the 1-sample delay found on all, every round and the '
        "observer's check 27 s median, 44 s worst (goal 20 s: missed); **stiction** (seeds 401-406): 4 "
        'adequate, EKF within 0.19 degree, 2 refused (403, 406: the same joint stop); **delay** (401-402): 2 '
        'adequate, K 0.10 %, m 0.50 %, EKF 0.11 degree; **slack** (401-402): 2 refused by the observer (a '
        "delay fitted that the plant does not have: a false refusal). Main's fit before (seeds 301-320, all):"
        ' 9 adequate, 11 refused, 0 silent'),
}

README_ROWS: dict[str, str] = {
    "default_path": (
        '| the default path on every draw: `experiment` then `identify`, no options, fingers drawn +-20 % | '
        'seeds 1-60: finger3 60 of 60 exit 0 (12 hung fingers down by the experiment itself), springs within '
        '0.22 %, masses within 1.60 %; finger2 60 of 60, 0.13 % / 0.16 %; no non-physical value written '
        '(2026-12-04, load 3-8 with other jobs, cache warm) | [`default_path.py`](benchmarks/default_path.py)'
        ' |'),
    "force_realism": (
        '| force control on MuJoCo with every effect of a real hand (stick-slip, elastic cable with rotor and'
        ' 0.5 deg slack, tilt, torque constant 5 % off, encoder offset, torque 1 ms late), experiment -> '
        'identify -> control | sensor loop, fresh seeds 201-206: 6/6 on finger3 (RMSE after the rise <= 1.98 '
        '%, overshoot <= 8.4 %, rise <= 97 ms) and 6/6 on finger2; with the shipped file 0/6 on finger3 (the '
        'cable mode rings: no notch without the identified compliance); sensorless within 10 % on the '
        'fingers; the hand (seed 201) sensor within 0.22 %, sensorless 5.1-10.0 % (goal 5 %: missed) '
        '(2026-12-04, load 6-9) | [`force_realism.py`](benchmarks/force_realism.py) |'),
    "realism": (
        '| realism: identify and the EKF on MuJoCo plants drawn +-20 %, every effect at once with 0.5 deg '
        'slack and the torque 1 ms late, fresh seeds 401-420 | 14 adequate (K within 0.86 %, m within 6.24 %,'
        ' EKF within 0.47 deg on every joint), 2 silent misses (m 5.3, 6.2 %), 6 refused naming a joint stop;'
        " fit with the observer's check 27 s median (goal 20 s: missed) (2026-12-04, load 2-3, cache warm) | "
        '[`realism.py`](benchmarks/realism.py) |'),
}
