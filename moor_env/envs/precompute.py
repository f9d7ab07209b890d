"""``python -m moor_env.envs.precompute --config anchor-release --jobs 2``: solve and store the hanging
equilibria of every discrete scenario combination of an env config ahead of training
(see :mod:`moor_env.envs.equilibria`)."""

import sys

from moor_env.envs.equilibria import main

if __name__ == "__main__":
    sys.exit(main())
