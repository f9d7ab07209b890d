"""The speed-against-error study of ``benchmarks/speed_vs_error.py`` (the entry point): its cases
(:mod:`.cases`), the runs of both codes (:mod:`.runs`), fronts and errors (:mod:`.analysis`), the plots
(:mod:`.plots`), the findings in words (:mod:`.findings`) and docs/speed_vs_error.md (:mod:`.markdown`).
"""
