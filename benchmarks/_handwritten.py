"""The figures of the benchmarks not yet recorded by ``benchmarks/record.py``, as last written by hand (issue 36).

``docs/make_benchmarks.py`` uses an entry here only while ``benchmarks/results/NAME.json`` is missing or
``benchmarks/_summaries.py`` has no summary for it: ``PAGE[name]`` is the section's text (reStructuredText),
``README_ROWS[name]`` the README's headline row as it was. Once the benchmark is recorded and summarised, the
generated text replaces it: delete the entry then (``tests/test_benchmark_page.py`` says which are stale).
"""

from __future__ import annotations

PAGE: dict[str, str] = {
    "force_realism": (
        '2026-12-05, fresh seeds 201-206 (tuned on finger3 seed 1; the calibration on finger3 seeds 1, 4, 5),'
        ' cache warm, ``benchmarks/results/force_realism.json`` (fingers, 18.6 min, load 4.7-7.8) and ``force'
        '_realism.hand.json`` (``--models "" --hand-seeds 201,...,206``, 42 min, load 7-11): finger3 sensor ('
        'identified + compensation) **6/6**, RMSE 1.56 % median (1.99 worst), overshoot 7.7 (8.6) %, rise 92 '
        '(94) ms; the rigid design and the shipped file 0/6 (the cable rings at 250 Hz: 32-34 % of the step);'
        ' sensorless 6/6 within 10 % (6.3 % median, 7.5 worst; calibrated once against the fingertip sensor 1'
        ".8 / 4.1 %; the shipped file 28 / 39 %); finger2: seed 204's fit lost its basin (not converged), on "
        'the other five sensor 5/5 (RMSE 0.43 %, overshoot 1.4 %, rise 68 ms), sensorless 5/5 (4.8 / 5.5 %; c'
        "alibrated 0.86 / 1.9 %; the shipped file 1/6). The hand (29 of 30 chain fits converged; the grasp's "
        "references from the drawn hand's probe, ``control.grasp_limits``): sensor within 0.3 % on 5/6 seeds "
        "-- seed 203's index lets go of the cylinder at its lowered 0.35 N step in the compensated loop (the "
        'rigid design and the shipped file hold it) --; sensorless uncalibrated **0/6** within 5 % (6.5-9.8 %'
        " worst, every chain above the torque constant's 4.8 % floor); calibrated (``Compensation(force_scale"
        '=)`` from ``control.force_scale_of``) **5/6** (2.4-3.9 %; seed 203 5.9 %); the shipped file 21-55 %'),
}

README_ROWS: dict[str, str] = {
    "force_realism": (
        '| force control on MuJoCo with every effect of a real hand (stick-slip, elastic cable with rotor and'
        ' 0.5 deg slack, tilt, torque constant 5 % off, encoder offset, torque 1 ms late), experiment -> iden'
        'tify -> control | fresh seeds 201-206: sensor loop 6/6 on finger3 (RMSE after the rise <= 1.99 %, ov'
        "ershoot <= 8.6 %, rise <= 94 ms), 5/5 on finger2 (seed 204's fit lost its basin); the shipped file 0"
        '/6 on finger3; sensorless within 10 % on the fingers (uncalibrated; 4.1 % worst calibrated once on t'
        "he fingertip sensor); the hand: sensor within 0.3 % on 5/6 seeds (203's index lets go), sensorless 0"
        "/6 within 5 % (the torque constant's 4.8 % floor), 5/6 calibrated (2026-12-05, load 5-11) | [`force_"
        'realism.py`](benchmarks/force_realism.py) |'),
}
