"""`flexmvm cache info | clear`: the disk cache of FE models and bases (flexmvm.setup_cache)."""

from __future__ import annotations

import click


@click.group("cache")
def command() -> None:
    """Disk cache of setup results (FE models, bases): $FLEXMVM_CACHE_DIR or ~/.cache/flexmvm."""


@command.command("info")
def info() -> None:
    """Path, number of entries and size of the cache."""
    from flexmvm import setup_cache

    found = setup_cache.info()
    state = "" if setup_cache.enabled() else f" (bypassed: {setup_cache.ENV_OFF} is set)"
    click.echo(f"cache: {found.path}{state}")
    click.echo(f"entries: {found.n_entries}")
    click.echo(f"size: {found.size_mb:.1f} MB")


@command.command("clear")
def clear() -> None:
    """Delete every cache entry."""
    from flexmvm import setup_cache

    n = setup_cache.clear()
    click.echo(f"removed {n} entries from {setup_cache.cache_dir()}")
