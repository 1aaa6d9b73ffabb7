#!/usr/bin/env python3
"""The camera side of the NUCLEO-F446RE rig: find the ball in each image and send one
9-byte frame per image to the board's USART1 RX (PA10, 115 200 Bd 8N1):

    A5 5A  seq  flags  x_lo x_hi  y_lo y_hi  crc8

seq: image counter (wraps at 256); flags bit 0: ball found; x, y: centroid, image column
and row in 1/16 px (u16 little-endian, rows grow downwards); crc8: CRC-8/SMBUS (poly 0x07,
init 0) of the six bytes from seq. The reference encoder is
dexter_drivers::camera::CameraFrame::encode (drivers/src/camera.rs).

A sketch for a host camera (a USB camera on a PC or a Raspberry Pi, a USB-serial adapter's
TX to PA10, common ground): OpenCV finds the largest blob in an HSV colour range, pyserial
sends the frame. The controller faults `Stale` when frames come less often than
`dexter board SCENE` says (100 frames/s for scenes/line-juggler.toml), and its estimator
assumes the latency it prints: measure your camera's (exposure to the last byte sent).

    python3 frames.py --selftest                  # the encoder against a known frame
    python3 frames.py --port /dev/ttyUSB0 --camera 0
"""
import argparse
import sys


def crc8_smbus(data):
    crc = 0
    for byte in data:
        crc ^= byte
        for _ in range(8):
            crc = ((crc << 1) ^ 0x07) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc


def encode(seq, found, x_px, y_px):
    """One frame: seq 0..255, found bool, the centroid in pixels (>= 0)."""
    sub = lambda px: min(int(px * 16 + 0.5), 0xFFFF)
    x, y = sub(x_px), sub(y_px)
    body = bytes([seq & 0xFF, 1 if found else 0, x & 0xFF, x >> 8, y & 0xFF, y >> 8])
    return bytes([0xA5, 0x5A]) + body + bytes([crc8_smbus(body)])


def selftest():
    # drivers/src/camera.rs's test vector: seq 7, x 80.5 px, y 100.25 px; the CRC 0xD0 is
    # the remainder of the six bytes times x^8 divided by x^8 + x^2 + x + 1 (long division)
    want = bytes([0xA5, 0x5A, 7, 1, 0x08, 0x05, 0x44, 0x06, 0xD0])
    got = encode(7, True, 80.5, 100.25)
    if got != want:
        sys.exit(f"encode: {got.hex()} != {want.hex()}")
    print("ok")


def run(port, camera, hsv_low, hsv_high):
    import cv2  # OpenCV: apt-get install python3-opencv
    import numpy as np
    import serial  # pyserial: apt-get install python3-serial

    link = serial.Serial(port, 115200)
    cap = cv2.VideoCapture(camera)
    seq = 0
    while True:
        ok, image = cap.read()
        if not ok:
            sys.exit("the camera delivered no image")
        mask = cv2.inRange(cv2.cvtColor(image, cv2.COLOR_BGR2HSV),
                           np.array(hsv_low), np.array(hsv_high))
        m = cv2.moments(mask, binaryImage=True)
        found = m["m00"] > 20  # at least 20 pixels of the ball's colour
        x, y = (m["m10"] / m["m00"], m["m01"] / m["m00"]) if found else (0.0, 0.0)
        link.write(encode(seq, found, x, y))
        seq = (seq + 1) & 0xFF


if __name__ == "__main__":
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--selftest", action="store_true")
    p.add_argument("--port", default="/dev/ttyUSB0")
    p.add_argument("--camera", type=int, default=0)
    p.add_argument("--hsv-low", type=int, nargs=3, default=[5, 120, 120])  # an orange ball
    p.add_argument("--hsv-high", type=int, nargs=3, default=[25, 255, 255])
    a = p.parse_args()
    selftest() if a.selftest else run(a.port, a.camera, a.hsv_low, a.hsv_high)
