"""Python tooling for the hapfluid device wire protocol (firmware_bridge/protocol.md)."""
from .codec import (CanAssembler, WireError, can_encode, canfd_decode, canfd_encode, crc8, crc16,
                    decode_packet, encode_packet)

__all__ = ["CanAssembler", "WireError", "can_encode", "canfd_decode", "canfd_encode", "crc8", "crc16",
           "decode_packet", "encode_packet"]
