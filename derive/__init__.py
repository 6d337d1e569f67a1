"""SymPy derivation of the quadrotor model with a moving centre of gravity.

Run ``python -m derive`` (or ``make derive``) to rewrite ``generated/``.
Nothing in the runtime package ``quadcog`` imports this package.
"""
