"""Publishing, the top layer: the report pipeline that runs the chapters and publishes their
figures and pages (:mod:`.report`; its HTML pages in :mod:`.website`, each chapter's exported by
:mod:`.export`, the index in :mod:`.index`; the PDF in :mod:`.paper`), the course edition (:mod:`.course`, with the exercises'
reference answers in :mod:`.answers`) and the arm panel (:mod:`.panel`, computed in
:mod:`.panel_compute`, served by :mod:`.panel_server`).

Only the command line (:mod:`nfarm.__main__`) is above it.
"""
