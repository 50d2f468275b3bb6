"""The simulation as a user drives it: :class:`~ti_golf.sim.simulation.Simulation` (the balls, the
steps, changes between runs), its saved runs (:mod:`.saved_run`) and results (:mod:`.results`),
on the contact solvers (:mod:`ti_golf.solvers`) and the physics (:mod:`ti_golf.physics`)."""
