"""Stages: one module per stage, each a function (inputs, parameters) -> output files."""
