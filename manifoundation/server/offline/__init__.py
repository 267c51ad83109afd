"""Offline work on files: the batch command's request reading, result store and worker pools (local or Ray Data).

``pool`` (rows in, rows out, a local process pool) and ``ray_pool`` (the same over a Ray Data actor pool) know
nothing of requests: data generation runs its shards through them too. ``items``, ``store``, ``synthesis`` and
``batch`` are the batch command's: files → rows → the service's worker core → one result file per request.
Ray is imported only inside ``ray_pool``'s functions (an optional extra: ``pip install 'manifoundation[ray]'``).
"""
