"""gRPC beside HTTP: the `manifoundation.v1` service over the same queue, contract and rules (docs/grpc.md).

Imports grpcio; nothing outside this package (the app's lifespan imports it when the gRPC port is on).
"""
