#!/usr/bin/env python3
"""Strict check of a KML written by openable_trajectory: well-formed XML in the KML 2.2 namespace, one
trajectory LineString through PATH_POINTS coordinates, LOOPS loop Placemarks of which AGREE are styled as
agreeing, every coordinate a valid longitude,latitude,altitude. Exit 0 when all holds, 1 with the reason."""
import sys
import xml.etree.ElementTree as ET

NS = {"k": "http://www.opengis.net/kml/2.2"}


def coordinates(text):
    points = []
    for item in text.split():
        lon, lat, alt = (float(v) for v in item.split(","))
        if not (-180.0 <= lon <= 180.0 and -90.0 <= lat <= 90.0):
            raise ValueError("coordinate out of range: " + item)
        points.append((lon, lat, alt))
    return points


def main(path, path_points, loops, agree):
    root = ET.parse(path).getroot()
    if root.tag != "{%s}kml" % NS["k"]:
        raise ValueError("root element is %s, expected kml in the KML 2.2 namespace" % root.tag)
    document = root.find("k:Document", NS)
    styles = {s.get("id") for s in document.findall("k:Style", NS)}
    if not {"trajectory", "loop_agrees", "loop_disagrees"} <= styles:
        raise ValueError("styles missing: %s" % styles)
    tracks = document.findall("k:Placemark", NS)
    if len(tracks) != 1 or tracks[0].find("k:LineString", NS) is None:
        raise ValueError("expected one trajectory Placemark with a LineString")
    track = coordinates(tracks[0].find("k:LineString/k:coordinates", NS).text)
    if len(track) != path_points:
        raise ValueError("trajectory has %d points, expected %d" % (len(track), path_points))
    placemarks = document.findall("k:Folder/k:Placemark", NS)
    if len(placemarks) != loops:
        raise ValueError("%d loop placemarks, expected %d" % (len(placemarks), loops))
    agreeing = 0
    for p in placemarks:
        style = p.find("k:styleUrl", NS).text
        if style not in ("#loop_agrees", "#loop_disagrees"):
            raise ValueError("loop placemark with style " + style)
        agreeing += style == "#loop_agrees"
        point = coordinates(p.find("k:MultiGeometry/k:Point/k:coordinates", NS).text)
        line = coordinates(p.find("k:MultiGeometry/k:LineString/k:coordinates", NS).text)
        if len(point) != 1 or len(line) != 2 or line[0] != point[0]:
            raise ValueError("loop placemark %s: expected a Point on the first of 2 line points" % p.find("k:name", NS).text)
        if point[0] not in track or line[1] not in track:
            raise ValueError("loop placemark %s is not on the trajectory" % p.find("k:name", NS).text)
    if agreeing != agree:
        raise ValueError("%d loops styled as agreeing, expected %d" % (agreeing, agree))


if __name__ == "__main__":
    try:
        main(sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]))
    except Exception as e:  # any failure is a test failure with its reason
        print("check_kml: %s: %s" % (type(e).__name__, e))
        sys.exit(1)
    print("check_kml: ok")
