"""Test-wide settings: property tests draw the same examples on every run.

CI must be deterministic: hypothesis derives its examples from each test's
own name instead of a fresh random seed, so a run passes or fails the same
way on every machine. An example that once failed stays in its test as an
``@example``.
"""

from hypothesis import settings

settings.register_profile("robotlib", derandomize=True, print_blob=True)
settings.load_profile("robotlib")
