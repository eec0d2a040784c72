"""Shared test configuration."""
import os

from hypothesis import settings

settings.register_profile("ci", max_examples=60, deadline=None, derandomize=True)  # reproducible CI
settings.register_profile("long", max_examples=5000, deadline=None)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))
