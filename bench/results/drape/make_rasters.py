# The rasters of bench/results/drape (pip install numpy tifffile; run in the output folder):
# inn_imagery.tif, 2400x2400 RGB over N47E011 (1.5" pixels, EPSG:4326, a smooth pattern), and
# inn_landcover.tif, 1200x1200 ESA WorldCover codes (3" pixels) in blocks.
import numpy as np, tifffile


def write_geotiff(name, img, photometric):
    """A GeoTIFF over the whole tile N47E011: north-west corner 11°E 48°N, EPSG:4326."""
    d = 1.0 / img.shape[0]
    extratags = [
        (33550, 'd', 3, (d, d, 0.0), False),  # ModelPixelScale
        (33922, 'd', 6, (0.0, 0.0, 0.0, 11.0, 48.0, 0.0), False),  # ModelTiepoint
        (34735, 'H', 16, (1, 1, 0, 3, 1024, 0, 1, 2, 1025, 0, 1, 1, 2048, 0, 1, 4326), False),
    ]
    tifffile.imwrite(name, img, photometric=photometric, extratags=extratags)


y, x = np.mgrid[0:2400, 0:2400].astype(np.float32)
r = (120 + 60 * np.sin(x / 37.0) * np.cos(y / 53.0)).astype(np.uint8)
g = (140 + 50 * np.sin((x + y) / 71.0)).astype(np.uint8)
b = (90 + 40 * np.cos((x - y) / 29.0)).astype(np.uint8)
write_geotiff('inn_imagery.tif', np.stack([r, g, b], axis=-1), 'rgb')

y, x = np.mgrid[0:1200, 0:1200]
codes = np.array([10, 30, 40, 50, 60, 80], dtype=np.uint8)
idx = ((x // 97) + (y // 131) * 3 + ((x * y) // 40000)) % len(codes)
write_geotiff('inn_landcover.tif', codes[idx], 'minisblack')
print('wrote inn_imagery.tif, inn_landcover.tif')
