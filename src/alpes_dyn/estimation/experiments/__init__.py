"""The experiments: what is done to the hand so that its parameters can be fitted, and the record it leaves. The
recording's CSV format (:mod:`.recording`: encoder counts, q_m = (2 pi / counts_per_rev) counts, report eq. 3.13;
the motor torques; the fingertip force of eq. 2.13), the experiment's settings (:mod:`.design`), its torque signals
(:mod:`.multisine`: a multisine per motor and its dither), the bias trimmed on the finger at the static equilibrium
of eq. 2.11 (:mod:`.trim`), the experiment simulated (:mod:`.experiment`) and adapted to the finger it runs on
(:mod:`.adapt`, ``alpes-dyn experiment``'s default), the whole hand in one record (:mod:`.hand_experiment`), the
encoder's excursion check (:mod:`.excursion`) and the seeded draws of a hand within its tolerances (:mod:`.draws`);
on a hand through the hardware interface, with no truth: the guarded session (:mod:`.hand_session`), the
calibration of its rest and range (:mod:`.calibration`), the experiment trimmed and guarded on it (:mod:`.on_hand`)
and in two orientations, the hand turned between the runs and the runs joined (:mod:`.turned`).
Nothing here imports the observers or the fit: they read what this sub-package writes."""
