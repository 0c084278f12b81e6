"""LINK_NODE_STATUS (message 8) for pymavlink 2.4.50, whose dialects leave
MAVLink's work-in-progress messages out: the message class as pymavlink's
generator writes one, from common.xml's definition, with the CRC extra the
mavlink crate's dialect has (117; a wrong one and mavping would drop every
frame as a bad CRC). `install(mavlink)` registers it in pymavlink's map so
pymavlink decodes it too.
"""
import struct

ID = 8
CRC_EXTRA = 117
# Declared order, then wire order (largest types first).
FIELDS = ["timestamp", "tx_buf", "rx_buf", "tx_rate", "rx_rate", "rx_parse_err", "tx_overflows",
          "rx_overflows", "messages_sent", "messages_received", "messages_lost"]
WIRE = ["timestamp", "tx_rate", "rx_rate", "messages_sent", "messages_received", "messages_lost",
        "rx_parse_err", "tx_overflows", "rx_overflows", "tx_buf", "rx_buf"]
TYPES = {"timestamp": "uint64_t", "tx_buf": "uint8_t", "rx_buf": "uint8_t", "tx_rate": "uint32_t",
         "rx_rate": "uint32_t", "rx_parse_err": "uint16_t", "tx_overflows": "uint16_t",
         "rx_overflows": "uint16_t", "messages_sent": "uint32_t",
         "messages_received": "uint32_t", "messages_lost": "uint32_t"}
FORMAT = "<QIIIIIHHHBB"


def install(mavlink):
    """The message class, registered in `mavlink` (a pymavlink dialect
    module) once."""
    existing = mavlink.mavlink_map.get(ID)
    if existing is not None:
        return existing

    class MAVLink_link_node_status_message(mavlink.MAVLink_message):
        id = ID
        msgname = "LINK_NODE_STATUS"
        fieldnames = FIELDS
        ordered_fieldnames = WIRE
        fieldtypes = [TYPES[f] for f in FIELDS]
        fielddisplays_by_name = {}
        fieldenums_by_name = {}
        fieldunits_by_name = {}
        native_format = bytearray(FORMAT.encode())
        orders = [WIRE.index(f) for f in FIELDS]
        lengths = [1] * len(FIELDS)
        array_lengths = [0] * len(FIELDS)
        crc_extra = CRC_EXTRA
        unpacker = struct.Struct(FORMAT)
        instance_field = None
        instance_offset = -1

        def __init__(self, *values, **named):
            mavlink.MAVLink_message.__init__(self, ID, "LINK_NODE_STATUS")
            self._fieldnames = FIELDS
            self._instance_field = None
            self._instance_offset = -1
            for name, value in zip(FIELDS, values):
                setattr(self, name, value)
            for name in FIELDS[len(values):]:
                setattr(self, name, named.get(name, 0))

        def pack(self, mav, force_mavlink1=False):
            payload = self.unpacker.pack(*(getattr(self, f) for f in WIRE))
            return self._pack(mav, CRC_EXTRA, payload, force_mavlink1=force_mavlink1)

    mavlink.mavlink_map[ID] = MAVLink_link_node_status_message
    return MAVLink_link_node_status_message


class SeqCount:
    """What a node received and lost of its link, by each sender's packet
    sequence: every frame is received (a duplicate too); a step forward of
    k skips k - 1 lost; a step back (a duplicate or a late frame) loses
    nothing and leaves the count where it was."""

    def __init__(self):
        self.received = self.lost = 0
        self.last = {}

    def frame(self, source, seq):
        self.received += 1
        last = self.last.get(source)
        if last is None:
            self.last[source] = seq
            return
        step = (seq - last) % 256
        if 0 < step < 128:
            self.lost += step - 1
            self.last[source] = seq
