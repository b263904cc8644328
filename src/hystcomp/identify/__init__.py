"""Identification from measured data, and the paper's identification signals."""
