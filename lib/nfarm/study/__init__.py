"""The study: study files and the data sets they define (:mod:`.datasets`), the library jobs a
sweep runs (:mod:`.jobs`) and the sweeps (:mod:`.sweep`), the spreads of compared numbers
(:mod:`.statistics`) and the summary of every method's held-out errors (:mod:`.summary`).

Imports every layer below; :mod:`nfarm.publishing` is above it.
"""
