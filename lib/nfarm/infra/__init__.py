"""Infrastructure, the bottom layer: the one strict reader of user files (:mod:`.reading`)
and the generic reader of a file's sections into dataclasses (:mod:`.typed`), the checks of the
arguments callers pass to the library (:mod:`.arguments`), project paths and atomic output
(:mod:`.paths`), the code digests that key every cache (:mod:`.provenance`), time limits for long
loops (:mod:`.limits`) and the allocator's tuning.

Imports nothing else of nfarm.
"""
