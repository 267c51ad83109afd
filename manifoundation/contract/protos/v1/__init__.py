"""Generated code of the `manifoundation.v1` proto (see `manifoundation.server.api.grpc.codegen`)."""
