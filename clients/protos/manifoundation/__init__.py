"""Generated code of the `manifoundation.v1` proto (see `service.grpc.codegen`)."""
