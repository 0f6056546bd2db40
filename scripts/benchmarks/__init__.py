"""The sections of scripts/benchmark.py, one module per thing measured (see that script's docstring)."""
