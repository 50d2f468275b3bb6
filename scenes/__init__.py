"""The bundled scenes (TOML) and their data files, shipped in the wheel as ``ti_golf.scene.data``."""
