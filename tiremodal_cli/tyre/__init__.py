"""The tyre model, its effects, the finite-element reference ring, the fit, sensitivity and the simulator (-> MeasuredModes, FitResult)."""
