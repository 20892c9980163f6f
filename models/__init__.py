"""Bundled vehicle model files (TOML); installed as ``profileopt.models``."""
