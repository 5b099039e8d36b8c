"""The lowest layer: errors, numeric settings, the YAML/schema layer and batching helpers.

Nothing here imports another spacearm layer.
"""
