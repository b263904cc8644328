"""The application layer: what a command runs, from records to fitted models and figures.

Each module returns structured results (dataclasses with the fitted objects, the figures
and the warnings); the command line words them.
"""
