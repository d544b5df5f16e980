"""The result cache: Merkle keys, an in-memory LRU and an on-disk store whose entries are
verified over every byte and read back into aligned, immutable memory."""
