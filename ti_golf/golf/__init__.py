"""Golf on the engine: launch-angle sweeps (:mod:`.sweep`), launch-monitor shots with their
roll-out (:mod:`.shots`, :mod:`.rollout`), dispersion (:mod:`.dispersion`), the TrackMan tour
table and the flights against it (:mod:`.trackman`, :mod:`.tour`), and the air model fitted to
it (:mod:`.aero_fit`). Built on the simulation core (:mod:`ti_golf.sim`)."""
