"""The commands' persistent compilation cache: where it goes, and off."""

from __future__ import annotations

from diffwear.cli.command import COMPILATION_CACHE, _compilation_cache


class _Config:
    def __init__(self):
        self.values: dict = {}

    def update(self, key, value):
        self.values[key] = value


class _Jax:
    def __init__(self):
        self.config = _Config()


def test_the_cache_folder_is_the_variables_or_the_users_cache(monkeypatch, tmp_path):
    jax = _Jax()
    monkeypatch.setenv(COMPILATION_CACHE, str(tmp_path / "here"))
    _compilation_cache(jax)
    assert jax.config.values["jax_compilation_cache_dir"] == str(tmp_path / "here")
    assert jax.config.values["jax_persistent_cache_min_compile_time_secs"] == 1.0

    jax = _Jax()
    monkeypatch.delenv(COMPILATION_CACHE)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    _compilation_cache(jax)
    assert jax.config.values["jax_compilation_cache_dir"] == str(tmp_path / "xdg" / "diffwear"
                                                                 / "jax")

    jax = _Jax()
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    _compilation_cache(jax)
    assert jax.config.values["jax_compilation_cache_dir"] == str(
        tmp_path / "home" / ".cache" / "diffwear" / "jax")


def test_off_leaves_the_cache_unset(monkeypatch):
    jax = _Jax()
    monkeypatch.setenv(COMPILATION_CACHE, "OFF")
    _compilation_cache(jax)
    assert jax.config.values == {}
