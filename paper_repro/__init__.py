"""Reproduces the analysis of the paper: equations 1-26 computed from the templates.

Run ``python -m paper_repro`` from the repository root; see ``__main__.py``.
"""
