"""The figures of the benchmarks not yet recorded by ``benchmarks/record.py``, as last written by hand (issue 36).

``docs/make_benchmarks.py`` uses an entry here only while ``benchmarks/results/NAME.json`` is missing or
``benchmarks/_summaries.py`` has no summary for it: ``PAGE[name]`` is the section's text (reStructuredText),
``README_ROWS[name]`` the README's headline row as it was. Once the benchmark is recorded and summarised, the
generated text replaces it: delete the entry then (``tests/test_benchmark_page.py`` says which are stale).
"""

from __future__ import annotations

PAGE: dict[str, str] = {
}

README_ROWS: dict[str, str] = {
    "force_realism": (
        '| force control on MuJoCo with every effect of a real hand (stick-slip, elastic cable with rotor and'
        ' 0.5 deg slack, tilt, torque constant 5 % off, encoder offset, torque 1 ms late), experiment -> iden'
        'tify -> control | fresh seeds 201-206, all 12 finger fits adequate: sensor loop 6/6 on finger3 (RMSE'
        ' after the rise <= 1.98 %, overshoot <= 8.5 %, rise <= 97 ms) and 6/6 on finger2; the shipped file 0'
        '/6 on finger3; sensorless within 10 % on the fingers (uncalibrated; 4.1 % worst calibrated once on t'
        'he fingertip sensor) (2026-12-05 14:32, load 4.8-7.0); the hand (15:20, load 0.4-2.0): sensor within'
        " 0.33 % on 6/6 seeds, sensorless 0/6 within 5 % (the torque constant's 4.8 % floor), 5/6 calibrated "
        '| [`force_realism.py`](benchmarks/force_realism.py) |'),
}
