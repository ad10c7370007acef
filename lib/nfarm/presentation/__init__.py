"""What a reader sees of a result: figures saved byte-reproducibly (:mod:`.plotting`), words
chosen from numbers (:mod:`.wording`) and rerun recordings (:mod:`.recording`).

Imports the layers below (learners, solvers, model, infra), never the study or publishing.
"""
