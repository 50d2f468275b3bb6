"""The benchmarks of ``ti-golf bench`` (:mod:`ti_golf.cli.bench`): one module per benchmark (sweep,
collide, pit, render, dispersion, startup), each with baselines timed in the same run, and their
helpers (:mod:`.common`, :mod:`.kernel_times`, the yardstick kernels of :mod:`.baseline`, the
independent integrations of :mod:`.reference`)."""
