"""The analysis floor: observability of the joints from the encoders (eq. 3.4-3.8, 3.14) and
identifiability of the parameters before any fit (structural rank, Fisher information)."""
