// nbhd's filters as a MeshLab 2020.09 filter plugin (MeshFilterInterface, IID
// "vcg.meshlab.MeshFilterInterface/1.0"): normals, curvatures as quality, the thesis' isotropic
// and anisotropic smoothing and the robust smoothing, on the vertices of the current mesh or
// point cloud. The work is done by nbhd's C ABI (include/nbhd.h); this class converts MeshLab's
// parameters and vertices and back. See meshlab_plugin/README.md.
#ifndef NBHD_FILTER_NBHD_H
#define NBHD_FILTER_NBHD_H

#include <common/interfaces.h>

class FilterNbhdPlugin : public QObject, public MeshFilterInterface
{
    Q_OBJECT
    MESHLAB_PLUGIN_IID_EXPORTER(MESH_FILTER_INTERFACE_IID)
    Q_INTERFACES(MeshFilterInterface)

public:
    enum {
        FP_NORMALS,
        FP_CURVATURES,
        FP_SMOOTH_ISOTROPIC,
        FP_SMOOTH_ANISOTROPIC,
        FP_SMOOTH_ROBUST,
    };

    FilterNbhdPlugin();

    QString pluginName() const override;
    QString filterName(FilterIDType filter) const override;
    QString filterInfo(FilterIDType filter) const override;
    QString filterScriptFunctionName(FilterIDType filter) override;
    FilterClass getClass(QAction* a) override;
    FILTER_ARITY filterArity(QAction*) const override;
    int getRequirements(QAction* a) override;
    int getPreConditions(QAction*) const override;
    int postCondition(QAction* a) const override;
    void initParameterSet(QAction* a, MeshModel& m, RichParameterList& par) override;
    bool applyFilter(QAction* a, MeshDocument& md, const RichParameterList& par,
                     vcg::CallBackPos* cb) override;

private:
    bool fail(FilterIDType id, const QString& what);
};

#endif
