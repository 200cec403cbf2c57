// libfilter_nbhd.so loaded as MeshLab loads it (QPluginLoader, qobject_cast to
// MeshFilterInterface) and driven directly, for what meshlabserver cannot show: the plugin's
// metadata, every filter's progress through vcg::CallBackPos, cancelling (MeshLab 2020.09's own
// callbacks never ask for it), errors with the mesh left unchanged, and the relative units.
//
//   test_plugin_direct PLUGIN.so MESH.ply
#include <common/interfaces.h>
#include <common/meshmodel.h>

#include "ply_ascii.hpp"

#include <QApplication>
#include <QJsonObject>
#include <QPluginLoader>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace {

int failures = 0;
void check(bool ok, const std::string& what)
{
    std::printf("  %s %s\n", ok ? "ok  " : "FAIL", what.c_str());
    if (!ok) ++failures;
}

// What MeshLab's callback saw; cancelAt >= 0 makes it return false from that percentage on.
std::vector<int> seen;
int cancelAt = -1;
bool record(const int pos, const char*)
{
    seen.push_back(pos);
    return cancelAt < 0 || pos < cancelAt;
}

std::vector<float> coords(const CMeshO& m)
{
    std::vector<float> c;
    for (const CVertexO& v : m.vert) c.insert(c.end(), {v.cP()[0], v.cP()[1], v.cP()[2]});
    return c;
}
std::vector<float> normals(const CMeshO& m)
{
    std::vector<float> c;
    for (const CVertexO& v : m.vert) c.insert(c.end(), {v.cN()[0], v.cN()[1], v.cN()[2]});
    return c;
}

void fill(MeshModel& mm, const plyio::Mesh& src, float scale)
{
    CMeshO& m = mm.cm;
    m.Clear();
    vcg::tri::Allocator<CMeshO>::AddVertices(m, src.n());
    for (size_t i = 0; i < src.n(); ++i) {
        m.vert[i].P() = Point3m(scale * src.xyz[3 * i], scale * src.xyz[3 * i + 1], scale * src.xyz[3 * i + 2]);
        m.vert[i].N() = Point3m(0, 0, 0);
    }
    vcg::tri::UpdateBounding<CMeshO>::Box(m);
}

}  // namespace

int main(int argc, char** argv)
{
    if (argc != 3) {
        std::fprintf(stderr, "usage: test_plugin_direct PLUGIN.so MESH.ply\n");
        return 2;
    }
    qputenv("QT_QPA_PLATFORM", "offscreen");
    QApplication app(argc, argv);

    std::printf("== loading %s with QPluginLoader\n", argv[1]);
    QPluginLoader loader(argv[1]);
    const QString iid = loader.metaData().value("IID").toString();
    check(iid == MESH_FILTER_INTERFACE_IID, "Qt plugin metadata IID " + iid.toStdString());
    QObject* instance = loader.instance();
    check(instance != nullptr, "QPluginLoader::instance() " + loader.errorString().toStdString());
    auto* plugin = qobject_cast<MeshFilterInterface*>(instance);
    check(plugin != nullptr, "qobject_cast<MeshFilterInterface*>");
    if (failures) return 1;
    GLLogStream log;
    plugin->setLog(&log);
    const QList<QAction*> actions = plugin->actions();
    check(actions.size() == 5, "five filters");
    for (QAction* a : actions) {
        const bool known = plugin->getClass(a) != MeshFilterInterface::Generic &&
                           plugin->filterArity(a) == MeshFilterInterface::SINGLE_MESH &&
                           plugin->getRequirements(a) != int(MeshModel::MM_UNKNOWN) &&
                           plugin->postCondition(a) != int(MeshModel::MM_UNKNOWN);
        check(known, "class, arity, requirements, postcondition of '" + a->text().toStdString() + "'");
    }

    const plyio::Mesh src = plyio::readPly(argv[2]);
    MeshDocument md;
    MeshModel* mm = md.addNewMesh("", "test");
    fill(*mm, src, 1.0f);

    std::printf("== progress and results of every filter (%zu vertices)\n", src.n());
    for (QAction* a : actions) {
        fill(*mm, src, 1.0f);
        RichParameterList par;
        plugin->initParameterSet(a, md, par);
        seen.clear();
        cancelAt = -1;
        const std::vector<float> before = coords(mm->cm);
        const bool ok = plugin->applyFilter(a, md, par, record);
        const std::string name = a->text().toStdString();
        check(ok, name + ": applied with the dialog's defaults " + plugin->errorMsg().toStdString());
        check(!seen.empty() && std::is_sorted(seen.begin(), seen.end()) && seen.front() >= 0 && seen.back() == 100,
              name + ": progress non-decreasing in [0, 100], ends at 100 (" + std::to_string(seen.size()) + " calls)");
        const std::vector<float> n = normals(mm->cm);
        bool unit = true;
        for (size_t i = 0; i < src.n(); ++i)
            unit = unit && std::fabs(std::sqrt(n[3 * i] * n[3 * i] + n[3 * i + 1] * n[3 * i + 1] + n[3 * i + 2] * n[3 * i + 2]) - 1) < 1e-4;
        check(unit, name + ": unit vertex normals written");
        const bool moved = coords(mm->cm) != before;
        const bool smoothing = plugin->getClass(a) & MeshFilterInterface::Smoothing;
        check(moved == smoothing, name + (smoothing ? ": vertices moved" : ": vertices not moved"));
    }

    QAction* aniso = actions[3];
    std::printf("== cancelling '%s' at 50%%\n", aniso->text().toStdString().c_str());
    {
        fill(*mm, src, 1.0f);
        RichParameterList par;
        plugin->initParameterSet(aniso, md, par);
        const std::vector<float> before = coords(mm->cm), nBefore = normals(mm->cm);
        seen.clear();
        cancelAt = 50;
        const bool ok = plugin->applyFilter(aniso, md, par, record);
        cancelAt = -1;
        check(!ok && plugin->errorMsg().contains("cancelled"), "returns false, errorMsg: " + plugin->errorMsg().toStdString());
        check(!seen.empty() && seen.back() >= 50 && seen.back() < 100, "stopped at " + std::to_string(seen.empty() ? -1 : seen.back()) + "%");
        check(coords(mm->cm) == before && normals(mm->cm) == nBefore, "mesh unchanged");
    }

    std::printf("== errors reach MeshLab as errorMsg, the mesh unchanged\n");
    struct Bad { int filter; const char* param; bool isInt; float value; const char* expect; };
    const Bad bad[] = {
        {3, "k", true, 0, "k must be at least 1"},
        {3, "k", true, -3, "'k' must be >= 0"},
        {3, "epsilon", false, -1, "epsilon"},
        {3, "lambda", false, 0, "lambda"},
        {4, "k_plane", true, 5, "k_plane"},
        {0, "epsilon", false, 0.001f, "no neighbourhood reached 3 points"},
    };
    for (const Bad& b : bad) {
        fill(*mm, src, 1.0f);
        RichParameterList par;
        plugin->initParameterSet(actions[b.filter], md, par);
        if (b.isInt) par.setValue(b.param, IntValue(int(b.value)));
        else par.setValue(b.param, FloatValue(b.value));
        const std::vector<float> before = coords(mm->cm), nBefore = normals(mm->cm);
        const bool ok = plugin->applyFilter(actions[b.filter], md, par, nullptr);
        const QString msg = plugin->errorMsg();
        check(!ok && (msg.contains(b.expect) || msg.contains(QString(b.expect).toLower())) &&
                  coords(mm->cm) == before && normals(mm->cm) == nBefore,
              std::string(b.param) + " = " + std::to_string(b.value) + ": " + msg.toStdString());
    }

    std::printf("== relative units: the same defaults on the mesh scaled by 1000\n");
    {
        RichParameterList par;
        fill(*mm, src, 1.0f);
        plugin->initParameterSet(aniso, md, par);
        plugin->applyFilter(aniso, md, par, nullptr);
        const std::vector<float> small = coords(mm->cm);
        fill(*mm, src, 1000.0f);
        plugin->applyFilter(aniso, md, par, nullptr);
        const std::vector<float> large = coords(mm->cm);
        double worst = 0, extent = 0;
        for (size_t i = 0; i < small.size(); ++i) {
            worst = std::max(worst, std::fabs(double(large[i]) / 1000.0 - small[i]));
            extent = std::max(extent, std::fabs(double(small[i])));
        }
        char b[160];
        std::snprintf(b, sizeof b, "smoothing commutes with scaling: max difference %.3g (extent %.3g)", worst, extent);
        check(worst <= 1e-4 * extent, b);
    }
    std::printf(failures ? "%d check(s) failed\n" : "all checks passed\n", failures);
    return failures ? 1 : 0;
}
