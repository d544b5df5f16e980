"""``graphvision cache info|prune|clear``."""

from __future__ import annotations

import argparse

from graphvision.cli.exits import EXIT_OK
from graphvision.cli.utf8_paths import refuse_cache_dir_not_utf8


def cmd_cache(args: argparse.Namespace) -> int:
    from graphvision.cache.disk import DiskStore
    from graphvision.locations import default_cache_dir

    refuse_cache_dir_not_utf8(args.cache_dir)
    folder = default_cache_dir() if args.cache_dir is None else args.cache_dir
    store = DiskStore(folder, args.cache_max_bytes)
    if args.action == "info":
        info = store.info()
        print(
            f"directory: {info.directory}\nentries:   {info.entries}\n"
            f"size:      {info.bytes / 2**20:.1f} MiB of {info.max_bytes / 2**20:.0f} MiB"
        )
    elif args.action == "prune":
        freed = store.prune(args.max_bytes if args.max_bytes is not None else store.max_bytes)
        print(f"freed {freed / 2**20:.1f} MiB")
    else:
        print(f"removed {store.clear()} entries from {store.directory}")
    return EXIT_OK
