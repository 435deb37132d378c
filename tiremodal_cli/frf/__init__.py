"""The FRF stage: hit checks, force/exponential windows, H1 and coherence (-> FRFResult)."""
