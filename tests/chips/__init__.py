"""Tests of the register-level chip models."""
