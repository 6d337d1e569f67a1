"""Layer stacks: flight stacks and peer suites in the loop. Shared helpers for third-party
trees (``vendor``: finding a tree by argument, environment variable or the vendor tarball,
unpacking a tarball into the cache by its SHA-256) and their builds (``build``: cache-keyed
builds of several C sources into one shared library, the compiler's first error line), under
these names; they live in ``quadcog.codegen.third_party``, which the embedded firmware builds
(a lower layer) use too."""
from quadcog.stacks.build import build_library, c_function, first_error_line
from quadcog.stacks.vendor import find_tree, tree_digest, unpack_tarball, vendor_dir

__all__ = ["build_library", "c_function", "first_error_line", "find_tree", "tree_digest",
           "unpack_tarball", "vendor_dir"]
