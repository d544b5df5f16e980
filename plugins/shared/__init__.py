"""The layer every family shares: input checks, parameter types, drawing helpers, boxes
(IoU, NMS, coding), and the compiled separable filters. Not a family: it registers
no node."""
