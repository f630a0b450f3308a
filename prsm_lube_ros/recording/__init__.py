"""Low-level reading of recordings: the MCAP container and the contract's CDR messages.

The public entry point is :mod:`prsm_lube_ros.bag_reader`.
"""
