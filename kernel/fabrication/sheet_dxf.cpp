// SPDX-License-Identifier: GPL-3.0-or-later
// Cut sheets as DXF, written with dxflib (Debian's libdxflib-dev, the DXF library of QCAD): the
// header, tables, blocks and objects of an AutoCAD 2000 file are its job; this file only says
// which entities go on which layer.
#include <dxflib/dl_dxf.h>
#include <dxflib/dl_writer_ascii.h>

#include <cstdio>
#include <string>

#include "gridshell/fabrication/kit_export.h"

namespace gridshell {
namespace {

/// dxflib writes through DL_WriterA, which owns an output file; this one collects the group
/// codes in memory instead (its file is /dev/null), so a sheet is bytes like every other view.
class StringWriter : public DL_WriterA {
 public:
  StringWriter() : DL_WriterA("/dev/null", DL_Codes::AC1015) {}
  void dxfReal(int code, double value) const override {
    char text[40];
    std::snprintf(text, sizeof text, "%.10g", value);
    std::string s = text;
    if (s.find_first_of(".eE") == std::string::npos && s.find("inf") == std::string::npos &&
        s.find("nan") == std::string::npos)
      s += ".0";  // a real, not an integer
    put(code, s);
  }
  void dxfInt(int code, int value) const override { put(code, std::to_string(value)); }
  void dxfHex(int code, int value) const override {
    char text[20];
    std::snprintf(text, sizeof text, "%X", static_cast<unsigned>(value));
    put(code, text);
  }
  void dxfString(int code, const char* value) const override { put(code, value); }
  void dxfString(int code, const std::string& value) const override { put(code, value); }
  std::string take() { return std::move(text_); }

 private:
  void put(int code, const std::string& value) const {
    char group[16];
    std::snprintf(group, sizeof group, "%3d\n", code);
    text_ += group;
    text_ += value;
    text_ += '\n';
  }
  mutable std::string text_;
};

const char* layer_name(SheetLayer layer) { return layer == SheetLayer::Cut ? "CUT" : "ENGRAVE"; }

}  // namespace

std::string sheet_dxf(const SheetDrawing& drawing) {
  DL_Dxf dxf;
  StringWriter writer;
  DL_WriterA& dw = writer;
  dxf.writeHeader(dw);
  dw.dxfString(9, "$INSUNITS");
  dw.dxfInt(70, 4);  // millimetres
  dw.dxfString(9, "$MEASUREMENT");
  dw.dxfInt(70, 1);  // metric
  dw.dxfString(9, "$EXTMIN");
  dw.dxfReal(10, 0);
  dw.dxfReal(20, 0);
  dw.dxfReal(30, 0);
  dw.dxfString(9, "$EXTMAX");
  dw.dxfReal(10, drawing.width);
  dw.dxfReal(20, drawing.height);
  dw.dxfReal(30, 0);
  dw.sectionEnd();
  dw.sectionTables();
  dxf.writeVPort(dw);
  dw.tableLinetypes(3);
  dxf.writeLinetype(dw, DL_LinetypeData("BYBLOCK", "BYBLOCK", 0, 0, 0.0));
  dxf.writeLinetype(dw, DL_LinetypeData("BYLAYER", "BYLAYER", 0, 0, 0.0));
  dxf.writeLinetype(dw, DL_LinetypeData("CONTINUOUS", "Continuous", 0, 0, 0.0));
  dw.tableEnd();
  dw.tableLayers(3);
  dxf.writeLayer(dw, DL_LayerData("0", 0),
                 DL_Attributes("", DL_Codes::black, 100, "CONTINUOUS", 1.0));
  dxf.writeLayer(dw, DL_LayerData("CUT", 0),
                 DL_Attributes("", DL_Codes::red, 100, "CONTINUOUS", 1.0));
  dxf.writeLayer(dw, DL_LayerData("ENGRAVE", 0),
                 DL_Attributes("", DL_Codes::blue, 100, "CONTINUOUS", 1.0));
  dw.tableEnd();
  dw.tableStyle(1);
  dxf.writeStyle(dw, DL_StyleData("Standard", 0, 0, 1.0, 0.0, 0, 2.5, "txt", ""));
  dw.tableEnd();
  dxf.writeView(dw);
  dxf.writeUcs(dw);
  dw.tableAppid(1);
  dxf.writeAppid(dw, "ACAD");
  dw.tableEnd();
  dxf.writeDimStyle(dw, 1, 1, 1, 1, 1);
  dxf.writeBlockRecord(dw);
  dw.tableEnd();
  dw.sectionEnd();
  dw.sectionBlocks();
  for (const char* block : {"*Model_Space", "*Paper_Space", "*Paper_Space0"}) {
    dxf.writeBlock(dw, DL_BlockData(block, 0, 0.0, 0.0, 0.0));
    dxf.writeEndBlock(dw, block);
  }
  dw.sectionEnd();
  dw.sectionEntities();
  for (const SheetPolyline& p : drawing.polylines) {
    const DL_Attributes attributes(layer_name(p.layer), 256, -1, "BYLAYER", 1.0);
    dxf.writePolyline(
        dw, DL_PolylineData(static_cast<int>(p.points.size()), 0, 0, p.closed ? 1 : 0), attributes);
    for (size_t i = 0; i < p.points.size(); ++i)
      dxf.writeVertex(dw, DL_VertexData(p.points[i].x(), p.points[i].y(), 0,
                                        i < p.bulges.size() ? p.bulges[i] : 0));
    dxf.writePolylineEnd(dw);
  }
  for (const SheetCircle& c : drawing.circles)
    dxf.writeCircle(dw, DL_CircleData(c.centre.x(), c.centre.y(), 0, c.radius),
                    DL_Attributes(layer_name(c.layer), 256, -1, "BYLAYER", 1.0));
  for (const SheetText& t : drawing.texts)
    dxf.writeText(dw,
                  DL_TextData(t.position.x(), t.position.y(), 0, t.position.x(), t.position.y(), 0,
                              t.height, 1.0, 0, 0, 0, t.text, "Standard", t.angle),
                  DL_Attributes(layer_name(t.layer), 256, -1, "BYLAYER", 1.0));
  dw.sectionEnd();
  dxf.writeObjects(dw);
  dxf.writeObjectsEnd(dw);
  dw.dxfEOF();
  return writer.take();
}

}  // namespace gridshell
