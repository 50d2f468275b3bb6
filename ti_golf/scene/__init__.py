"""Scene input in plain Python, no Taichi: the key declarations and tables (:mod:`.schema`,
:mod:`.keys`, :mod:`.checks`), TOML files and ``--set`` overrides read into a validated
:class:`~ti_golf.scene.schema.Scene` (:mod:`.loader`), the initial balls (:mod:`.balls`), the
terrain's heights (:mod:`.terrain`), the air and weather (:mod:`.air`, :mod:`.weather`), launch
monitors (:mod:`.launch_monitor`), and the keys as documents, references and a JSON Schema."""
