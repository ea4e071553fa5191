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
        '| force control on MuJoCo with every effect of a real hand: experiment -> identify -> control | fresh'
        ' seeds 201-206, 12 of 12 finger fits adequate: the sensor loop 6/6 on finger3 (RMSE <= 1.98 %, overshoot'
        ' <= 8.5 %, rise <= 97 ms) and 6/6 on finger2, sensorless within 10 %; the hand\'s sensor loop within'
        ' 0.33 % on 6/6 (2026-12-05, load 0.4-7.0) | [`force_realism.py`](benchmarks/force_realism.py) |'),
}
