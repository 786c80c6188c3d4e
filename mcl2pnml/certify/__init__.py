"""Missions proven from their parts, without exploring their state space (sections 2.3-2.5).

The paper's argument is compositional: a task pattern or a control
structure that keeps the interface contract (:mod:`mcl2pnml.analysis.checking.contract`),
joined with children that keep it, keeps it. This package owns that
argument as code: the proofs of the library's templates, each checked once
against the contract with its children reduced (Fig. 3) and stored with a
digest of the net it was checked on (:mod:`mcl2pnml.certify.templates`).

May import :mod:`mcl2pnml.core`, :mod:`mcl2pnml.language` (the templates),
:mod:`analysis` (the contract) and :mod:`mcl2pnml.io`; only the facade
imports it.
"""
