"""Third-party source trees: where one is, and unpacking a vendor tarball into the cache.

The names of ``quadcog.codegen.third_party`` (the one tree finder, shared with the embedded
firmware builds), under the names the stacks have used.
"""
from quadcog.codegen.third_party import VENDOR_ENV, find_tree, tree_digest, unpack_tarball, vendor_dir

__all__ = ["VENDOR_ENV", "vendor_dir", "unpack_tarball", "find_tree", "tree_digest"]
